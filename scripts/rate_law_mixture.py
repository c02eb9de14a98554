#!/usr/bin/env python3
"""The rate law's calibration (docs/theory.md "Rate-dependent strength").

One material point of the 3D bond mixture at nu = 1/4 (LPS and PMB coincide there) strained
homogeneously in uniaxial stress at the axial strain rate R, its bonds following the bilinear
law from s_t to s_u = r s_t (solver/include/breccia/solver/pd_physics.hpp softening_damage).
The model of calibration.cpp's homogeneous_tension_peak, written again with the rate law:
when a direction first passes its static onset, its onset and ultimate stretch are multiplied
by F = DIF(c x its stretch rate) (fib Model Code 2010, strength_dif) and kept; the lateral
strain keeps the lateral stress zero (iterated with the damage at each step).

Prints, for each r: the static peak per unit onset Phi(r), and the peak with the law over
DIF(R) x the static peak, with c = 1 (the bond's own rate) and with c = Phi(r)
(pd_kernels.hpp bond_rate_factor). Usage: rate_law_mixture.py [r ...] (default 3 5 10 30 100).
Directions: 180 over a quarter circle (the sum is axisymmetric); steps of s_t/100.
"""
import math
import sys

import numpy as np

THETA = (np.arange(180) + 0.5) * (0.5 * np.pi / 180)
WEIGHT = np.sin(THETA)
NX2 = np.cos(THETA) ** 2
NL2 = 1.0 - NX2


def dif(rate):
    rate = np.asarray(rate, float)
    out = np.ones_like(rate)
    low = (rate > 1e-6) & (rate <= 10.0)
    high = rate > 10.0
    out[low] = (rate[low] / 1e-6) ** 0.018
    out[high] = 0.0062 * np.cbrt(rate[high] / 1e-6)
    return out


def damage(s, onset, ultimate):
    with np.errstate(divide="ignore", invalid="ignore"):
        d = 1.0 - (onset / s) * (ultimate - s) / (ultimate - onset)
    return np.where(s <= onset, 0.0, np.where(s >= ultimate, 1.0, d))


def peak(r, rate, law, c=1.0):
    """Peak sigma_xx over the initial modulus (units of the static onset). law: None or 'fib'."""
    onset = np.ones_like(THETA)
    ultimate = np.full_like(THETA, r)
    fixed = np.zeros_like(THETA, bool)
    d = np.zeros_like(THETA)
    de = 1.0 / 100.0
    dt = de / rate
    lateral, best, best_ex, s_prev, modulus = 0.0, 0.0, 0.0, None, None
    for step in range(1, 200000):
        ex = step * de
        for _ in range(30):
            s = ex * NX2 + lateral * NL2
            on, ul = onset, ultimate
            if law:
                stretch_rate = (s - s_prev) / dt if s_prev is not None else rate * NX2
                raise_now = (~fixed) & (s > onset)
                factor = dif(c * stretch_rate)
                on = np.where(raise_now, onset * factor, onset)
                ul = np.where(raise_now, ultimate * factor, ultimate)
            d_new = np.maximum(d, damage(s, on, ul))
            keep = 1.0 - d_new
            a = np.sum(WEIGHT * keep * NX2 * NL2)
            b = np.sum(WEIGHT * keep * NL2 * NL2)
            lateral_new = -ex * a / b
            if abs(lateral_new - lateral) < 1e-12:
                lateral = lateral_new
                break
            lateral = lateral_new
        s = ex * NX2 + lateral * NL2
        newly = (~fixed) & (d_new > 0)
        onset = np.where(newly, on, onset)
        ultimate = np.where(newly, ul, ultimate)
        fixed |= newly
        d = d_new
        s_prev = s
        sigma = np.sum(WEIGHT * (1.0 - d) * s * NX2)
        if modulus is None:
            modulus = sigma / ex
        if sigma > best:
            best, best_ex = sigma, ex
        if sigma < 0.97 * best and ex > 1.3 * best_ex:
            break
    return best / modulus


def phi_table(r):
    """pd_kernels.hpp bond_rate_factor's table, interpolated in ln r."""
    at = [1.0, 1.5, 2.0, 3.0, 5.0, 7.0, 10.0, 20.0, 30.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
    phi = [1.0, 1.0842, 1.1434, 1.2248, 1.3228, 1.3838, 1.4449, 1.5521, 1.6073, 1.6692, 1.7402, 1.7976, 1.8558, 1.8891]
    if r <= at[0]:
        return phi[0]
    for q in range(1, len(at)):
        if r <= at[q]:
            t = math.log(r / at[q - 1]) / math.log(at[q] / at[q - 1])
            return phi[q - 1] + t * (phi[q] - phi[q - 1])
    return phi[-1]


if __name__ == "__main__":
    ratios = [float(a) for a in sys.argv[1:]] or [3.0, 5.0, 10.0, 30.0, 100.0]
    for r in ratios:
        static = peak(r, 1.0, None)
        print(f"r = {r:g}: Phi = {static:.4f}", flush=True)
        for rate in (3.3, 30.0, 100.0, 1000.0):
            scale = static * dif([rate])[0]
            own = peak(r, rate, "fib") / scale
            calibrated = peak(r, rate, "fib", phi_table(r)) / scale
            print(f"  R = {rate:g} /s: peak / (DIF(R) Phi) = {own:.3f} (c = 1), {calibrated:.3f} (c = Phi(r))", flush=True)
