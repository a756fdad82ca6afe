# SPDX-License-Identifier: Apache-2.0
"""Chi-square test of a direction sampler against its pdf, in NumPy only (no SciPy).

Directions are binned on the equal-area square (every bin subtends the same solid angle, 4 pi / R^2).
A bin's expected count integrates the pdf over the bin with S x S stratified sub-samples. Bins expected
to receive fewer than `min_expected` samples are pooled into one so that the statistic's
chi-square approximation holds; the p-value comes from the regularized upper incomplete gamma function.
"""
import math

import numpy as np

import envpis


def gamma_q(a, x):
    """Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a), for a > 0, x >= 0."""
    if x <= 0:
        return 1.0
    log_prefix = a * math.log(x) - x - math.lgamma(a)
    if x < a + 1:  # the series of P(a, x) converges fast here
        term = total = 1.0 / a
        k = a
        while abs(term) > abs(total) * 1e-15:
            k += 1
            term *= x / k
            total += term
        return max(0.0, 1.0 - total * math.exp(log_prefix))
    # Lentz's continued fraction of Q(a, x)
    tiny = 1e-300
    b = x + 1 - a
    c = 1 / tiny
    d = 1 / b
    h = d
    for i in range(1, 10000):
        an = -i * (i - a)
        b += 2
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1 / d
        delta = d * c
        h *= delta
        if abs(delta - 1) < 1e-15:
            break
    return math.exp(log_prefix) * h


def chi2_pvalue(stat, dof):
    """P(X >= stat) for X chi-square distributed with dof degrees of freedom."""
    return gamma_q(dof / 2.0, stat / 2.0)


def expected_counts(pdf, count, resolution=32, sub=4):
    """Expected samples per equal-area bin (resolution x resolution) for `count` samples of `pdf`
    (a function of an M x 3 direction array returning M densities per solid angle). The samplers'
    densities are constant over each of the table's N x N fine texels, so the integral is exact when
    resolution * sub is a multiple of N (sub-samples at texel centres)."""
    r, s = resolution, sub
    # sub-sample centres of every bin, in bin-major order
    k = (np.arange(r * s) + 0.5) / (r * s)
    uu, vv = np.meshgrid(k, k)  # vv varies along rows (y), uu along columns (x)
    points = np.stack([uu.ravel(), vv.ravel()], axis=1)
    dens = np.asarray(pdf(envpis.equal_area_square_to_sphere(points)), dtype=np.float64)
    dens = dens.reshape(r, s, r, s).mean(axis=(1, 3))  # [bin y, bin x]
    return dens * (4 * math.pi / (r * r)) * count


def observed_counts(dirs, resolution=32):
    """Samples per equal-area bin (resolution x resolution, [bin y, bin x])."""
    uv = envpis.equal_area_sphere_to_square(dirs)
    idx = np.clip((np.asarray(uv) * resolution).astype(np.int64), 0, resolution - 1)
    flat = idx[:, 1] * resolution + idx[:, 0]
    return np.bincount(flat, minlength=resolution * resolution).reshape(resolution, resolution)


def chi2_test(observed, expected, min_expected=5.0):
    """Pearson's chi-square of observed vs expected counts after pooling low-expectation bins.
    Returns (p-value, statistic, degrees of freedom). Observed samples in bins with zero expectation
    give p = 0 (the sampler produced directions its pdf says are impossible)."""
    obs = np.asarray(observed, dtype=np.float64).ravel()
    exp = np.asarray(expected, dtype=np.float64).ravel()
    if np.any((exp <= 0) & (obs > 0)):
        return 0.0, math.inf, 0
    # pool every bin expected below min_expected into one; if even that is short, into the
    # smallest of the others
    low = exp < min_expected
    pooled_o, pooled_e = obs[low].sum(), exp[low].sum()
    obs, exp = obs[~low], exp[~low]
    if pooled_e >= min_expected or len(exp) == 0:
        obs, exp = np.append(obs, pooled_o), np.append(exp, pooled_e)
    elif pooled_e > 0:
        i = int(np.argmin(exp))
        obs[i] += pooled_o
        exp[i] += pooled_e
    stat = float(np.sum((obs - exp) ** 2 / exp))
    dof = len(exp) - 1
    if dof < 1:
        return 1.0, stat, dof
    return chi2_pvalue(stat, dof), stat, dof
