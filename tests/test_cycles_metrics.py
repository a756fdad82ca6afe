# SPDX-License-Identifier: Apache-2.0
"""Unit test of scripts/cycles_metrics.py, the pure functions of the Cycles side by side
(scripts/cycles_compare.py): quartiles, slope, tail, targets, tables. Needs numpy, not Blender.

  python3 tests/test_cycles_metrics.py      (ctest: cycles_metrics; exit 77 = skipped without numpy)
"""
import math
import os
import sys
import unittest

try:
    import numpy as np
except ImportError:
    print("test_cycles_metrics: numpy is missing: skipped")
    sys.exit(77)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import cycles_metrics as M  # noqa: E402


def grey(values):
    """[h, w] -> [h, w, 3] with the same value in every channel."""
    v = np.asarray(values, dtype=np.float64)
    return np.repeat(v[:, :, None], 3, axis=2)


def rows_for(spps, relmses, q4=None, seconds=1.0):
    """summarise() input: one seed per spp with the given relMSE, quartile 4 = q4 (or relMSE)."""
    q4 = q4 or relmses
    return [{"spp": s, "seeds": [{"relmse_sphere": v, "relmse_all": v / 2, "quartiles": [v, v, v, w],
                                  "worst": 10 * v, "over_10x": 0, "seconds": seconds * s / spps[-1], "seed": 0}]}
            for s, v, w in zip(spps, relmses, q4)]


class Quartiles(unittest.TestCase):
    def test_equal_counts_by_rank(self):
        b = np.array([5.0, 1.0, 7.0, 3.0, 2.0, 8.0, 6.0, 4.0])
        q = M.brightness_quartiles(b)
        self.assertEqual(list(q), [2, 0, 3, 1, 0, 3, 2, 1])
        self.assertEqual(sorted(np.bincount(q)), [2, 2, 2, 2])

    def test_uneven_and_ties(self):
        q = M.brightness_quartiles(np.zeros(10))
        self.assertEqual(sorted(np.bincount(q, minlength=4)), [2, 2, 3, 3])
        q = M.brightness_quartiles(np.arange(10.0))
        self.assertEqual(q[-1], 3)  # the brightest pixel is in the brightest quartile
        self.assertEqual(q[0], 0)


class ImageMetrics(unittest.TestCase):
    def test_quartile_means_tail_and_mask(self):
        ref = grey([[1.0, 2.0], [3.0, 4.0]])
        image = ref.copy()
        image[1, 1] = 4.0 * 12  # the brightest pixel 11 x its value off: e = (44^2) / (16.01)
        image[0, 0] = 1.5       # the darkest: e = 0.25 / 1.01
        mask = np.array([[True, True], [True, True]])
        quartile = M.brightness_quartiles(ref.mean(axis=2)[mask])
        m = M.image_metrics(image, ref, mask, quartile)
        e_bright, e_dark = 44.0 ** 2 / 16.01, 0.25 / 1.01
        self.assertAlmostEqual(m["quartiles"][3], e_bright)
        self.assertAlmostEqual(m["quartiles"][0], e_dark)
        self.assertEqual(m["quartiles"][1:3], [0.0, 0.0])
        self.assertAlmostEqual(m["relmse_sphere"], (e_bright + e_dark) / 4)
        self.assertAlmostEqual(m["worst"], e_bright)
        self.assertEqual(m["over_10x"], 1)
        # Outside the mask a pixel counts in relmse_all only.
        mask2 = np.array([[True, True], [True, False]])
        m2 = M.image_metrics(image, ref, mask2, M.brightness_quartiles(ref.mean(axis=2)[mask2]))
        self.assertEqual(m2["over_10x"], 0)
        self.assertAlmostEqual(m2["relmse_sphere"], e_dark / 3)
        self.assertAlmostEqual(m2["relmse_all"], (e_bright + e_dark) / 4)

    def test_ten_times_off_is_the_threshold(self):
        ref = grey([[1.0]])
        mask = np.array([[True]])
        q = np.zeros(1, dtype=np.int64)
        # e = 100 exactly is not "more than 10x off"
        d = math.sqrt(100 * 1.01)
        self.assertEqual(M.image_metrics(ref + d * 0.999, ref, mask, q)["over_10x"], 0)
        self.assertEqual(M.image_metrics(ref + d * 1.001, ref, mask, q)["over_10x"], 1)


class Slope(unittest.TestCase):
    def test_power_law(self):
        spps = [1, 4, 16, 64, 256]
        self.assertAlmostEqual(M.loglog_slope(spps, [3.0 * s ** -1.5 for s in spps]), -1.5)
        # Only 16..256 count: a different 1 and 4 spp change nothing.
        self.assertAlmostEqual(M.loglog_slope(spps, [1e9, 1e-9] + [2.0 * s ** -1.2 for s in spps[2:]]), -1.2)

    def test_least_squares(self):
        # log4 spacing: values 1, 1/4, 1/64 -> points (0, 0), (1, -1), (2, -3) in units of log 4: slope -1.5
        self.assertAlmostEqual(M.loglog_slope([16, 64, 256], [1.0, 0.25, 1.0 / 64]), -1.5)

    def test_not_measurable(self):
        self.assertIsNone(M.loglog_slope([16], [1.0]))
        self.assertIsNone(M.loglog_slope([1, 4], [1.0, 0.5]))
        self.assertIsNone(M.loglog_slope([16, 64, 256], [1.0, 0.0, 0.1]))


class SummaryAndTargets(unittest.TestCase):
    def scene(self, product, cycles, product_q4=None, cycles_q4=None, product_seconds=1.0):
        spps = [16, 64, 256]
        return {"map_name": "sunrise", "alpha": 0.25, "agreement": {
                    "mean_relative_difference": 0.004, "ratio_of_means": 1.0, "p95_relative_difference": 0.01},
                "renderers": {M.CYCLES: M.summarise(rows_for(spps, cycles, cycles_q4)),
                              "envpis product": M.summarise(rows_for(spps, product, product_q4,
                                                                     seconds=product_seconds))}}

    def test_summarise(self):
        s = M.summarise([{"spp": 16, "seeds": [
            {"relmse_sphere": v, "relmse_all": v, "quartiles": [v, v, v, 2 * v], "worst": v, "over_10x": n,
             "seconds": t} for v, n, t in [(1.0, 0, 0.5), (3.0, 2, 0.2), (2.0, 5, 0.3)]]}])
        r = s["spp"][0]
        self.assertEqual((r["relmse_sphere"], r["over_10x"], r["quartiles"][3]), (2.0, 2.0, 4.0))
        self.assertAlmostEqual(s["seconds_per_spp"], 0.2 / 16)  # the fastest seed
        self.assertAlmostEqual(r["efficiency_sphere"], 1 / (2.0 * 0.2))

    def test_targets_met_and_not(self):
        # product: half Cycles' relMSE, the same slope, the same time: efficiency 2x; its highlight 2x worse.
        sc = self.scene([0.5, 0.5 / 8, 0.5 / 64], [1.0, 1.0 / 8, 1.0 / 64],
                        product_q4=[2.0, 2.0 / 8, 2.0 / 64], cycles_q4=[1.0, 1.0 / 8, 1.0 / 64])
        t = M.targets(sc)
        self.assertEqual([round(v, 6) for v in t["relmse"]], [0.5, 0.5])
        self.assertEqual([round(v, 6) for v in t["q4"]], [2.0, 2.0])
        self.assertEqual([round(v, 6) for v in t["efficiency"]], [2.0, 2.0])
        self.assertEqual(t["met"], {"relmse": True, "q4": False, "slope": True, "efficiency": True})
        # A shallower slope is not met; twice the time halves efficiency.
        sc = self.scene([0.5, 0.1, 0.02], [1.0, 1.0 / 8, 1.0 / 64], product_seconds=2.0)
        t = M.targets(sc)
        self.assertFalse(t["met"]["slope"])
        self.assertFalse(t["met"]["efficiency"])
        self.assertFalse(t["met"]["relmse"])  # 0.02 / (1/64) > 1 at 256 spp

    def test_tables(self):
        sc = self.scene([0.5, 0.5 / 8, 0.5 / 64], [1.0, 1.0 / 8, 1.0 / 64])
        table = M.results_table([sc], [1, 4, 16, 64, 256])
        lines = table.strip().splitlines()
        self.assertEqual(len(lines), 4)
        self.assertEqual(len({l.count("|") for l in lines}), 1)  # every row has the header's columns
        self.assertIn("relMSE 16/64/256 spp", lines[0])
        self.assertIn("| sunrise, 0.25 | Cycles |", lines[2])
        self.assertIn("| | product |", lines[3].replace("|  |", "| |"))
        tt = M.targets_table([sc]).strip().splitlines()
        self.assertEqual(len(tt), 3)
        self.assertIn("0.50 / 0.50: met", tt[2])
        md = M.markdown({"size": 32, "threads": 2, "sampler": "sobol", "pattern": "PMJ", "ref_strategy": "mis",
                         "ref_spp": 4096, "seeds": 3, "spp": [16, 64, 256]}, [sc], "note")
        self.assertIn(table, md)


if __name__ == "__main__":
    unittest.main()
