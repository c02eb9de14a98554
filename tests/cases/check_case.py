"""Run one benchmark case's coarse test variant and check a robust measure.

    check_case.py CASE --source ROOT --bin BIN_DIR --work DIR [--python PY]

Runs ROOT/cases/CASE/run.sh with VARIANT=test, OUT=DIR (the whole CLI chain: specimen,
breccia-solve, breccia-post, the case's report.py), then checks DIR/report.json. Every
band below carries its reason; the published numbers, with their sources, are in each
case's README.md and docs/benchmarks.md. Exit 0: pass; 1: a check failed; 2: the chain failed.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

FAILURES = []


def check(ok, what):
    print(("PASS " if ok else "FAIL ") + what)
    if not ok:
        FAILURES.append(what)


def glass_branching(rep):
    # The run (VARIANT=test) is the shipped quick lattice, dx = 1/3 mm (m = 3), to 28 us. It
    # was dx = 0.5 mm (m = 2) until a 0.35% smaller time step (a change of the stable-step
    # method) made that run not fork at all: at m = 2 whether the tip splits is chaotic. At
    # m = 3 the fork holds (65.8 / 66.1 mm at safety 0.80 / 0.78; cases/glass-branching/
    # README.md); the bands below are unchanged.
    run = rep["runs"][0]
    br = run["branching"]
    c_r = rep["rayleigh_speed_m_s"]
    check(br.get("branched", False), "the crack branches within 28 us at 2 MPa (Bobaru & Zhang 2015: one branching)")
    # One symmetric pair: Bobaru & Zhang 2015 show a single branching at 2 MPa (benchmarks.md 1a).
    check(br["max_bands_on_a_vertical_line"] == 2,
          f"one branch pair (bands on a vertical line = {br['max_bands_on_a_vertical_line']}, expected 2)")
    # Band: the crack must run before it can branch (it reaches ~0.5 c_R only after several
    # mm), and the fork position is sensitive: the 12 MPa / 135 J/m2 run, equal to this one
    # up to 0.7 % in sigma/sqrt(G0), forks at 85 mm (README); m = 2, 3, 4 give 64-65 mm.
    fork = br.get("fork_x_m", float("nan")) * 1e3
    check(55.0 <= fork <= 90.0, f"fork x = {fork:.1f} mm in [55, 90] mm")
    # Speed before branching: below 0.6 c_R (soda-lime branches at ~0.5 c_R, Bowden et al.
    # 1967 [R]; the Rayleigh speed bounds mode-I cracks) and above 0.25 c_R (a running crack,
    # not a creeping damage zone).
    v = run.get("mean_speed_before_branching_m_s", float("nan"))
    check(0.25 * c_r <= v <= 0.6 * c_r, f"mean tip speed before branching {v:.0f} m/s in [0.25, 0.6] c_R = "
          f"[{0.25 * c_r:.0f}, {0.6 * c_r:.0f}] m/s")


def kalthoff_winkler(rep):
    for label, notch in rep["notches"].items():
        length = notch.get("crack_length_m", 0.0) * 1e3
        check(length >= 20.0, f"{label} notch: a crack grew {length:.1f} mm (>= 20 mm) from the tip")
    # 70 deg in the experiment (Kalthoff & Winkler 1988), 65-72 deg in PD papers; the coarse
    # test lattice (dx 1.25 mm, delta 3.8 mm) bends the first millimetres of the path, which
    # the 5-25 mm fit includes: 55-80 deg separates a mode-II kink from a straight mode-I
    # extension (0 deg) or a crack along the impact (90 deg).
    angle = rep.get("mean_initial_angle_deg") or float("nan")
    check(55.0 <= angle <= 80.0, f"mean crack angle {angle:.1f} deg in [55, 80] deg")


def granite_blast(rep):
    runs = {r["run"]: r for r in rep["runs"]}
    a = rep["hole_radius_m"]
    g = runs["g0_200"]["final"]
    # Textbook critical stretch at mean G0 (1.9e-3 at delta 1.5 mm) against the hoop strain
    # of a pressurised hole, (1 + nu) p / E (a/r)^2 = 3.75e-3 (a/r)^2: exceeded only within
    # ~1.4 a statically, ~2 a with dynamic overshoot and the Weibull scatter (m = 1.5).
    check(1.2 * a <= g["crushed_radius_m"] <= 3.0 * a,
          f"G0 200: crushed zone radius {g['crushed_radius_m'] * 1e3:.2f} mm in [1.2, 3] hole radii")
    check(g["max_damaged_radius_m"] <= 0.010,
          f"G0 200: no damage beyond 10 mm (max {g['max_damaged_radius_m'] * 1e3:.1f} mm): no long radial cracks")
    s = runs["seed_s0"]["final"]
    # With the seed's critical stretch (1/sqrt(pi) lower) the seed reports "several dominant
    # radial cracks"; several = 2 to 10 crossing the 5 mm circle (about 4 hole radii).
    n = s["cracks_at_radius_mm"]["5"]
    check(2 <= n <= 10, f"seed s0: {n} radial cracks cross r = 5 mm (expected 2-10)")


def grady_ring(rep):
    runs = sorted(rep["runs"], key=lambda r: r["strain_rate_per_s"])
    lo, hi = runs[0], runs[-1]
    # More fragments at the higher rate: Grady's s ~ rate^(-2/3) predicts 4.6x between 1e3
    # and 1e4 /s; requiring only 1.3x keeps the test about the trend, not the exponent (the
    # README reports the fitted exponent, which differs).
    check(hi["fragments_kept"] >= 1.3 * lo["fragments_kept"],
          f"fragments at {hi['strain_rate_per_s']:.0e}/s ({hi['fragments_kept']}) >= 1.3 x at "
          f"{lo['strain_rate_per_s']:.0e}/s ({lo['fragments_kept']})")
    # Order of magnitude: Grady's energy balance bounds brittle fragment sizes from above
    # (flaw-controlled fragmentation gives smaller pieces), so s/s_Grady in [0.1, 1.5].
    for r in runs:
        q = r.get("size_over_grady", float("nan"))
        check(0.1 <= q <= 1.5, f"rate {r['strain_rate_per_s']:.0e}/s: mean size / Grady = {q:.2f} in [0.1, 1.5]")


CHECKS = {"glass-branching": glass_branching, "kalthoff-winkler": kalthoff_winkler,
          "granite-blast": granite_blast, "grady-ring": grady_ring}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("case", choices=sorted(CHECKS))
    p.add_argument("--source", required=True)
    p.add_argument("--bin", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--python", default="/usr/bin/python3")
    a = p.parse_args()
    os.makedirs(a.work, exist_ok=True)
    report = os.path.join(a.work, "report.json")
    if os.path.exists(report):
        os.remove(report)
    env = dict(os.environ, BRECCIA_BIN=a.bin, OUT=a.work, VARIANT="test", PYTHON=a.python,
               THREADS=os.environ.get("THREADS", "2"), MPLBACKEND="Agg")
    case_dir = os.path.join(a.source, "cases", a.case)
    start = time.time()
    proc = subprocess.run(["bash", "run.sh"], cwd=case_dir, env=env)
    print(f"{a.case}: run.sh exit {proc.returncode} after {time.time() - start:.1f} s")
    if proc.returncode != 0 or not os.path.exists(report):
        print("FAIL the case chain did not finish or wrote no report.json")
        return 2
    with open(report) as fh:
        CHECKS[a.case](json.load(fh))
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
