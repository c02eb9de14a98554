"""Synthetic horizontal accelerogram for cases/mps-cask-seismic (the Kobe 1995 record the
thesis used is not in our sources; any CSV in the same format can replace it).

    record.py OUT.csv [--pga 0.7] [--duration 8] [--dt 0.005] [--seed 1995]
              [--perturb 0.001 --perturb-seed 1]
              [--pulse-pgv 0.9 --pulse-period 1 --pulse-time 2 --pulse-gamma 2 --pulse-phase 0]

Generation, seeded so that it repeats: Gaussian white noise at dt, band-passed to 0.5-8 Hz
(its Fourier components outside the band set to zero: no phase shift), shaped by a trapezoidal
envelope (rise 1 s, strong motion to 40% of the duration, linear decay to the end; Amin &
Ang's form of a nonstationary record), a baseline correction (the slope of a least-squares
straight line fitted to the integrated velocity taken out of the acceleration: the velocity's
linear trend, not its end value, so the ground does not end at rest: the case's record ends
at 0.114 m/s, 13% of its 0.867 m/s peak ground velocity, 0.51 m from its start), scaled to the
peak ground acceleration `pga` (in g). Writes `time_s,acceleration_g` rows.

--perturb eps --perturb-seed s: a member of an ensemble of records that differ from the seed's
by less than any measurement of a record could tell: a second record made the same way from
`s` (same band, envelope and baseline correction), times eps of the first one's peak, is added
before the scaling to `pga` (README, "An ensemble over perturbed records").

--pulse-pgv V (m/s, default 0: none): adds a near-fault velocity pulse after the scaling, so
`pga` is the noise's peak and the record's peak is printed. The pulse is Mavroeidis &
Papageorgiou's (BSSA 93(3), 2003) wavelet, ground velocity
    v(t) = V/2 [1 + cos(2 pi (t - t0) / (gamma Tp))] cos(2 pi (t - t0) / Tp + nu),
for |t - t0| <= gamma Tp / 2, zero outside (Tp `--pulse-period`, t0 `--pulse-time`, gamma
`--pulse-gamma`, nu `--pulse-phase` in degrees); its acceleration, the exact derivative, is
continuous and zero at both ends, and for gamma = 2, nu = 0 the ground ends at rest where it
started. The perturbed records of an ensemble get the same pulse (the perturbation is in the
noise only).
"""
import argparse
import os

import numpy as np


def shaped(t, dt, duration, seed):
    """Band-passed, enveloped, baseline-corrected noise from `seed`, scaled to a peak of 1."""
    n = len(t)
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(n)
    spectrum = np.fft.rfft(noise)
    f = np.fft.rfftfreq(n, dt)
    spectrum[(f < 0.5) | (f > 8.0)] = 0.0
    acc = np.fft.irfft(spectrum, n)
    rise, strong = 1.0, 0.4 * duration
    env = np.where(t < rise, t / rise, np.where(t < strong, 1.0, np.maximum(0.0, (duration - t) / (duration - strong))))
    acc *= env
    # Baseline: remove the straight line that fits the velocity best.
    vel = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt)])
    slope, _ = np.polyfit(t, vel, 1)
    acc -= slope
    acc[0] = 0.0
    return acc / np.max(np.abs(acc))


def pulse_acceleration(t, pgv, period, t0, gamma, phase_deg):
    """Acceleration (m/s2) of the Mavroeidis-Papageorgiou velocity pulse (module docstring)."""
    tau = t - t0
    w, nu = 2.0 * np.pi / period, np.radians(phase_deg)
    inside = np.abs(tau) <= gamma * period / 2
    env, denv = 1.0 + np.cos(w * tau / gamma), -(w / gamma) * np.sin(w * tau / gamma)
    acc = 0.5 * pgv * (denv * np.cos(w * tau + nu) - env * w * np.sin(w * tau + nu))
    return np.where(inside, acc, 0.0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--pga", type=float, default=0.7)
    ap.add_argument("--duration", type=float, default=8.0)
    ap.add_argument("--dt", type=float, default=0.005)
    ap.add_argument("--seed", type=int, default=1995)
    ap.add_argument("--perturb", type=float, default=0.0)
    ap.add_argument("--perturb-seed", type=int, default=1)
    ap.add_argument("--pulse-pgv", type=float, default=0.0)
    ap.add_argument("--pulse-period", type=float, default=1.0)
    ap.add_argument("--pulse-time", type=float, default=2.0)
    ap.add_argument("--pulse-gamma", type=float, default=2.0)
    ap.add_argument("--pulse-phase", type=float, default=0.0)
    a = ap.parse_args()
    n = int(round(a.duration / a.dt)) + 1
    t = np.arange(n) * a.dt
    acc = shaped(t, a.dt, a.duration, a.seed)
    if a.perturb > 0.0:
        acc = acc + a.perturb * shaped(t, a.dt, a.duration, a.perturb_seed)
    acc[0] = 0.0
    acc *= a.pga / np.max(np.abs(acc))
    if a.pulse_pgv > 0.0:
        acc = acc + pulse_acceleration(t, a.pulse_pgv, a.pulse_period, a.pulse_time, a.pulse_gamma,
                                       a.pulse_phase) / 9.80665
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)  # the README's run/ folder, made here
    with open(a.out, "w") as f:
        f.write("time_s,acceleration_g\n")
        for ti, ai in zip(t, acc):
            f.write(f"{ti:.6f},{ai:.6f}\n")
    vel = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * a.dt)]) * 9.80665
    disp = np.concatenate([[0.0], np.cumsum(0.5 * (vel[1:] + vel[:-1]) * a.dt)])
    print(f"{a.out}: {n} rows, {a.duration} s, pga {np.max(np.abs(acc)):.3f} g, peak ground velocity {np.max(np.abs(vel)):.3f} m/s, "
          f"end velocity {vel[-1]:.4f} m/s, end displacement {disp[-1]:.3f} m")


if __name__ == "__main__":
    main()
