# SPDX-License-Identifier: Apache-2.0
"""Unit test of scripts/light_share_table.py on two generated compare outputs: the glossy objects are
selected by their alpha, the shares pooled by the median and the ratios by the geometric mean.

  python3 tests/test_light_share_table.py      (ctest: light_share_table)
"""
import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import light_share_table as L  # noqa: E402


def region(name, share, trimmed):
    return {"name": name, "light_variance_share": share, "relmse_trimmed": trimmed}


def write_run(out, scene_map, mis_comp, product):
    os.makedirs(os.path.join(out, scene_map))
    names = [r["name"] for r in mis_comp]
    metrics = {"regions": [{"name": n} for n in names],
               "equal_spp": {"strategies": [{"strategy": "mis-comp", "regions": mis_comp},
                                            {"strategy": "product", "regions": product}]}}
    with open(os.path.join(out, scene_map, "metrics.json"), "w") as f:
        json.dump(metrics, f)


class LightShareTable(unittest.TestCase):
    def test_pools_glossy_objects_only(self):
        with tempfile.TemporaryDirectory() as out:
            # plastic (alpha 0.15) is glossy, clay (diffuse) and chrome (alpha 0.0225) are not.
            write_run(out, "bunny--a", [region("plastic", 0.5, 0.4), region("clay", 0.9, 1.0)],
                      [region("plastic", 0.6, 0.2), region("clay", 0.9, 0.1)])
            write_run(out, "bunny--b", [region("plastic", 0.0, 0.9), region("chrome", 0.5, 1.0)],
                      [region("plastic", 0.2, 0.1), region("chrome", 0.5, 0.1)])
            rows = list(L.rows(out))
            self.assertEqual([r[1] for r in rows], ["plastic", "plastic"])
            self.assertAlmostEqual(rows[0][5], 2.0)  # 0.4 / 0.2
            self.assertAlmostEqual(rows[0][6], 2.0)  # 1 / (1 - 0.5)
            self.assertAlmostEqual(rows[1][5], 9.0)
            text = io.StringIO()
            with contextlib.redirect_stdout(text):
                L.main(out)
            # plastic: shares median 0.25 and 0.40, gain geomean(2, 9) = 4.24, bound geomean(2, 1) = 1.41.
            self.assertIn("| bunny | plastic | 0.150 | 2 | 0.25 | 0.40 | 4.24 | 1.41 |", text.getvalue())
            self.assertIn("object-maps gaining more than it: 1.", text.getvalue())  # 9 > 1; 2 is not > 2

    def test_no_glossy_object_is_an_error(self):
        with tempfile.TemporaryDirectory() as out:
            write_run(out, "bunny--a", [region("clay", 0.5, 0.4)], [region("clay", 0.6, 0.2)])
            with self.assertRaises(SystemExit) as e:
                L.main(out)
            self.assertIn("no glossy objects", str(e.exception.code))


if __name__ == "__main__":
    unittest.main()
