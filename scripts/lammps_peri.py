#!/usr/bin/env python3
"""LAMMPS PERI's own examples run side by side in LAMMPS and in Breccia (make lammps-peri).

The examples are Debian's lammps-examples `examples/peri/in.peri.pmb` and `in.peri.lps`:
a simple-cubic lattice (0.5 mm) cylinder of 3,487 particles, radius 5 mm, height 5 mm,
axis y, density 2200 kg/m3, horizon 1.5001 mm, struck by a rigid sphere (`fix indent`,
K = 1e17, R = 1.5 mm) moving at -100 m/s from y = 1.55 mm; dt 0.1 us, 1,000 steps.
PMB: c = 1.6863e22 N/m6 (= 18 K / (pi delta^4), K = 14.9 GPa). LPS: K = G = 14.9 GPa,
LAMMPS's influence function 1/|xi|.

Each example runs under three rules: `elastic` (no bond breaks), `fixed` (s0 = s00 =
5e-4, alpha = 0: the rule both codes share) and `silling-askari` (s0 = s00 - alpha s_min,
alpha = 0.25, the examples as shipped). Breccia runs each as:
  breccia  - Breccia's own modelling choices (sampled partial volumes out to delta plus a
             cell diagonal, no short-range forces);
  matched  - LAMMPS's choices: families cut at |xi| <= delta with LAMMPS's partial-volume
             ramp (model.partial_volume: lammps) and the short-range contact forces
             (model.short_range_forces: true).
The particles are LAMMPS's own (written by LAMMPS, converted to particles.h5). Breccia's
G0 is chosen so that its critical stretch equals s00 (docs/lammps-peri.md).

Writes OUT/comparison.csv, OUT/comparison.md and OUT/*.png (kinetic energy, indenter force
and damage against height along the axis). Usage:
  scripts/lammps_peri.py --build build [--out runs/lammps-peri] [--models pmb lps]
                         [--rules elastic fixed silling-askari] [--variants breccia matched]
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

LC = 0.0005          # lattice constant [m]
VOLUME = LC ** 3     # LAMMPS `set group all volume 1.25e-10`
DELTA = 0.0015001    # horizon [m]
DENSITY = 2200.0
K_BULK = 14.9e9      # both examples
C_PMB = 1.6863e22    # in.peri.pmb pair_coeff
S00 = 0.0005
ALPHA = 0.25
DT = 1.0e-7
STEPS = 1000
IND_K, IND_R, IND_Y0, IND_V = 1e17, 0.0015, 0.00155, -100.0

RULES = {"elastic": (1.0e3, 0.0), "fixed": (S00, 0.0), "silling-askari": (S00, ALPHA)}

# LAMMPS's modelling choices as Breccia options (docs/lammps-peri.md):
#   family       - model.partial_volume: lammps (|xi| <= delta, LAMMPS's ramp), and for PMB
#                  model.pmb_calibration: continuum (c as given, no discrete bulk calibration)
#   short-range  - model.short_range_forces: true
#   after-force  - model.break_check: after_force (a breaking bond pushes once more)
FEATURES = ("family", "short-range", "after-force")
VARIANTS = {
    "breccia": (),                                   # Breccia's defaults
    "matched": FEATURES,                             # every LAMMPS choice
    "no-family": ("short-range", "after-force"),     # matched less one choice at a time
    "no-short-range": ("family", "after-force"),
    "before-force": ("family", "short-range"),
}

LAMMPS_HEAD = """units si
boundary s s s
atom_style peri
atom_modify map array
neighbor 0.0010 bin
lattice sc 0.0005
region target cylinder y 0.0 0.0 0.0050 -0.0050 0.0 units box
create_box 1 target
create_atoms 1 region target
"""


def elastic_constants(model):
    """E and nu that give Breccia the examples' K (and G for LPS)."""
    if model == "pmb":
        # The K whose textbook micromodulus 18 K / (pi delta^4) is the input file's c exactly
        # (c = 1.6863e22 is 18 x 14.9 GPa / (pi delta^4) rounded to 5 digits).
        k_pmb = C_PMB * math.pi * DELTA ** 4 / 18.0
        return 3.0 * k_pmb * (1.0 - 2.0 * 0.25), 0.25  # bond-based: nu = 1/4
    G = K_BULK
    return 9.0 * K_BULK * G / (3.0 * K_BULK + G), (3.0 * K_BULK - 2.0 * G) / (2.0 * (3.0 * K_BULK + G))


def fracture_energy(model, s0):
    """G0 whose critical stretch is s0 in Breccia's calibration (solver/src/calibration.cpp):
    PMB, constant influence: G0 = pi c s0^2 delta^5 / 10; LPS, inverse influence (J_k = 1/k):
    G0 = 15 mu delta J5 s0^2 / (4 J4) = 3 mu delta s0^2."""
    if model == "pmb":
        return math.pi * C_PMB * s0 ** 2 * DELTA ** 5 / 10.0
    return 3.0 * K_BULK * DELTA * s0 ** 2


def run(cmd, cwd, log):
    t0 = time.time()
    with open(log, "w") as f:
        rc = subprocess.call(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT)
    if rc != 0:
        sys.exit(f"lammps_peri: {' '.join(cmd)} failed (rc {rc}); see {log}")
    return time.time() - t0


def lammps_particles(lmp, out):
    """LAMMPS's lattice, written by LAMMPS itself, as a Breccia particles.h5."""
    with open(os.path.join(out, "in.initial"), "w") as f:
        f.write(LAMMPS_HEAD + "write_dump all custom initial.dump id x y z modify sort id\n")
    run([lmp, "-in", "in.initial", "-log", "none", "-screen", "none"], out, os.path.join(out, "initial.log"))
    rows = np.loadtxt(os.path.join(out, "initial.dump"), skiprows=9)
    ids, pos = rows[:, 0].astype(np.int64), rows[:, 1:4]
    n = len(ids)
    path = os.path.join(out, "particles.h5")
    with h5py.File(path, "w") as f:
        f.attrs["format"] = np.bytes_("breccia-particles")
        f.attrs["format_version"] = np.int64(1)
        f.attrs["dimension"] = np.int64(3)
        f.attrs["thickness_m"] = 1.0
        f.attrs["units"] = np.bytes_("SI (m, m3, kg, s)")
        f.attrs["source"] = np.bytes_("LAMMPS examples/peri lattice sc 0.0005, cylinder y r 5 mm")
        f.attrs["content_id"] = np.bytes_("0000000000000000")
        f["particles/position"] = pos
        f["particles/volume"] = np.full(n, VOLUME)
        f["particles/spacing"] = np.full(n, LC)
        f["particles/material_id"] = np.zeros(n, dtype=np.int32)
        f.create_dataset("materials/names", data=["default"], dtype=h5py.string_dtype(encoding="ascii"))
    return ids, pos


def last_dump_frame(path):
    """The last frame of a LAMMPS custom dump (id x y z c_1), rows sorted by id."""
    lines = open(path).read().splitlines()
    start = max(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS")) + 1
    rows = np.array([[float(v) for v in l.split()] for l in lines[start:] if l.strip()])
    return rows[np.argsort(rows[:, 0])]


def lammps_run(lmp, out, model, rule, refine=1):
    s00, alpha = RULES[rule]
    name = f"lammps-{model}-{rule}" + (f"-dt{refine}" if refine > 1 else "")
    steps = STEPS * refine
    coeff = (f"{C_PMB} {DELTA} {s00} {alpha}" if model == "pmb" else f"{K_BULK} {K_BULK} {DELTA} {s00} {alpha}")
    text = LAMMPS_HEAD + f"""pair_style peri/{model}
pair_coeff * * {coeff}
set group all density {DENSITY}
set group all volume {VOLUME}
velocity all set 0.0 0.0 0.0 sum no units box
fix 1 all nve
variable y0 equal {IND_Y0}
variable vy equal {IND_V}
variable y equal "v_y0 + step*dt*v_vy"
fix 2 all indent {IND_K} sphere 0.0000 v_y 0.0000 {IND_R} units box
compute 1 all damage/atom
variable d5 atom "c_1 > 0.5"
compute dmg all reduce ave c_1
compute d5 all reduce ave v_d5
timestep {DT / refine}
thermo {10 * refine}
thermo_style custom step ke f_2[2] c_dmg c_d5
thermo_modify norm no
dump 1 all custom {steps} {name}.dump id x y z c_1
dump_modify 1 sort id
run {steps}
"""
    with open(os.path.join(out, f"{name}.in"), "w") as f:
        f.write(text)
    wall = run([lmp, "-in", f"{name}.in", "-log", f"{name}.log", "-screen", "none"], out,
               os.path.join(out, f"{name}.out"))
    hist, in_thermo = [], False
    for line in open(os.path.join(out, f"{name}.log")):
        w = line.split()
        if w[:2] == ["Step", "KinEng"]:
            in_thermo = True
            continue
        if in_thermo:
            if not w or not w[0].isdigit():
                in_thermo = False
                continue
            step = int(w[0])
            # LAMMPS PERI's masses are densities and its forces force densities: KE and the
            # indenter's force become J and N with the particle volume.
            hist.append((step * DT / refine, float(w[1]) * VOLUME, float(w[2]) * VOLUME))
        if line.startswith("Loop time"):
            wall = float(line.split()[3])
    final = last_dump_frame(os.path.join(out, f"{name}.dump"))
    return {"code": "lammps", "model": model, "rule": rule, "variant": "lammps", "damage": final[:, 4],
            "damage_count": final[:, 4], "history": np.array(hist), "wall_s": wall}


def breccia_run(solve, out, model, rule, variant, threads, refine=1):
    s00, alpha = RULES[rule]
    E, nu = elastic_constants(model)
    name = f"breccia-{model}-{rule}-{variant}" + (f"-dt{refine}" if refine > 1 else "")
    features = VARIANTS[variant]
    mdl = {"type": model, "horizon": f"{DELTA} m", "influence": "constant" if model == "pmb" else "inverse",
           "fracture": rule != "elastic"}
    if alpha:
        mdl["compressive_enhancement"] = alpha
    if "family" in features:
        mdl["partial_volume"] = "lammps"
        if model == "pmb":
            mdl["pmb_calibration"] = "continuum"
    if "short-range" in features:
        mdl["short_range_forces"] = True
    if "after-force" in features:
        mdl["break_check"] = "after_force"
    case = {
        "name": name,
        "specimen": {"particles": "particles.h5"},
        "model": mdl,
        "materials": [{"name": "default", "density": DENSITY, "youngs_modulus": E, "poisson_ratio": nu,
                       "fracture_energy": fracture_energy(model, s00) if rule != "elastic" else 0.0}],
        "indenter": {"radius": IND_R, "center": [0.0, IND_Y0, 0.0], "velocity": [0.0, IND_V, 0.0],
                     "stiffness": IND_K},
        "time": {"dt": DT / refine, "steps": STEPS * refine, "check_stability": False},
        "output": {"every": STEPS * refine, "history_every": 10 * refine,
                   "fields": ["displacement", "velocity", "damage"]},
    }
    with open(os.path.join(out, f"{name}.yaml"), "w") as f:
        json.dump(case, f, indent=1)  # JSON is YAML
    run_dir = os.path.join(out, name)
    shutil.rmtree(run_dir, ignore_errors=True)
    run([solve, f"{name}.yaml", "-o", name, "--threads", str(threads), "--quiet", "--backend", "cpu"], out,
        os.path.join(out, f"{name}.out"))
    hist = []
    with open(os.path.join(run_dir, "history.csv")) as f:
        for r in csv.DictReader(f):
            hist.append((float(r["time_s"]), float(r["kinetic_J"]), float(r["indenter_force_y_N"])))
    with h5py.File(os.path.join(run_dir, "results.h5"), "r") as f:
        last = sorted(f["output"].keys())[-1]
        damage = f[f"output/{last}/damage"][:]
        # LAMMPS's measure (compute damage/atom): the unweighted share of broken partners
        # within the horizon, from the bond list and its broken bits (docs/formats.md).
        offsets, partner = f["bonds/offsets"][:], f["bonds/neighbors"][:]
        bits = lambda name: np.unpackbits(f[name][:], bitorder="little")[:len(partner)].astype(bool)
        within = bits("bonds/within_horizon")
        broken = bits(f"output/{last}/broken")
        n = len(offsets) - 1
        owner = np.repeat(np.arange(n), np.diff(offsets))
        count = lambda mask: (np.bincount(owner[mask], minlength=n) + np.bincount(partner[mask], minlength=n))
        total = count(within)
        damage_count = count(within & broken) / np.maximum(total, 1)
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    return {"code": "breccia", "model": model, "rule": rule, "variant": variant, "damage": damage,
            "damage_count": damage_count, "history": np.array(hist), "wall_s": summary.get("wall_s", float("nan"))}


def axis_profile(pos, damage):
    """Mean damage of the particles within the sphere's radius of the axis, per lattice layer in y."""
    near = pos[:, 0] ** 2 + pos[:, 2] ** 2 <= IND_R ** 2 + 1e-12
    layers = np.round(pos[:, 1] / LC).astype(int)
    ys = sorted(set(layers[near]))
    return np.array([y * LC for y in ys]), np.array([damage[near & (layers == y)].mean() for y in ys])


def ke_mismatch(a, b):
    """Largest |KE_a - KE_b| over the history, relative to the largest KE of a."""
    n = min(len(a), len(b))
    return float(np.max(np.abs(a[:n, 1] - b[:n, 1])) / np.max(np.abs(a[:n, 1])))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default="runs/lammps-peri")
    ap.add_argument("--lmp", default=shutil.which("lmp") or "lmp")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--models", nargs="+", default=["pmb", "lps"], choices=["pmb", "lps"])
    ap.add_argument("--rules", nargs="+", default=list(RULES), choices=list(RULES))
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--dt-study", action="store_true",
                    help="also run the fixed rule at dt/2 and dt/4 (LAMMPS, matched, before-force): dt_study.csv")
    args = ap.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    solve = os.path.abspath(os.path.join(args.build, "bin", "breccia-solve"))
    ids, pos = lammps_particles(args.lmp, out)
    results = []
    for model in args.models:
        for rule in args.rules:
            print(f"lammps-peri: {model} {rule}: LAMMPS", flush=True)
            ref = lammps_run(args.lmp, out, model, rule)
            results.append(ref)
            for variant in args.variants:
                print(f"lammps-peri: {model} {rule}: Breccia {variant}", flush=True)
                results.append(breccia_run(solve, out, model, rule, variant, args.threads))
    rows = []
    for r in results:
        ref = next(x for x in results if x["code"] == "lammps" and x["model"] == r["model"] and x["rule"] == r["rule"])
        rows.append({
            "model": r["model"], "rule": r["rule"], "code": r["code"], "variant": r["variant"],
            "mean_damage": float(np.mean(r["damage"])), "fraction_above_0.5": float(np.mean(r["damage"] > 0.5)),
            "mean_damage_lammps_measure": float(np.mean(r["damage_count"])),
            "fraction_above_0.5_lammps_measure": float(np.mean(r["damage_count"] > 0.5)),
            "final_kinetic_J": float(r["history"][-1, 1]),
            "max_ke_difference_vs_lammps": 0.0 if r is ref else ke_mismatch(ref["history"], r["history"]),
            "wall_s": r["wall_s"]})
    write_tables(out, "comparison", rows, [
        ("model", "model", "{}"), ("rule", "rule", "{}"), ("code", "code", "{}"), ("variant", "variant", "{}"),
        ("mean damage", "mean_damage", "{:.4f}"), ("fraction > 0.5", "fraction_above_0.5", "{:.4f}"),
        ("mean damage, LAMMPS's measure", "mean_damage_lammps_measure", "{:.4f}"),
        ("fraction > 0.5, LAMMPS's measure", "fraction_above_0.5_lammps_measure", "{:.4f}"),
        ("final KE (J)", "final_kinetic_J", "{:.4g}"), ("max KE diff vs LAMMPS", "max_ke_difference_vs_lammps", "{:.1%}"),
        ("wall (s)", "wall_s", "{:.2f}")])
    plots(results, pos, out)
    if args.dt_study:
        dt_study(args, out, solve)


def dt_study(args, out, solve):
    """Does the break order's effect vanish with the time step? The fixed rule at dt, dt/2,
    dt/4 in LAMMPS and in Breccia with both orders (every other LAMMPS choice matched)."""
    rows = []
    for model in args.models:
        for refine in (1, 2, 4):
            runs = [lammps_run(args.lmp, out, model, "fixed", refine)]
            for variant in ("matched", "before-force"):
                print(f"lammps-peri: dt study {model} dt/{refine}: Breccia {variant}", flush=True)
                runs.append(breccia_run(solve, out, model, "fixed", variant, args.threads, refine))
            for r in runs:
                rows.append({"model": model, "dt_s": DT / refine, "code": r["code"], "variant": r["variant"],
                             "mean_damage": float(np.mean(r["damage_count"])),
                             "fraction_above_0.5": float(np.mean(r["damage_count"] > 0.5)), "wall_s": r["wall_s"]})
    for r in rows:
        r["dt_us"] = r["dt_s"] * 1e6
    write_tables(out, "dt_study", rows, [
        ("model", "model", "{}"), ("dt (us)", "dt_us", "{:.3g}"), ("code", "code", "{}"), ("variant", "variant", "{}"),
        ("mean damage (LAMMPS's measure)", "mean_damage", "{:.4f}"), ("fraction > 0.5", "fraction_above_0.5", "{:.4f}"),
        ("wall (s)", "wall_s", "{:.2f}")])


def write_tables(out, name, rows, columns):
    """OUT/NAME.csv (every field) and OUT/NAME.md (the columns: (title, key, format)), printed."""
    with open(os.path.join(out, f"{name}.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = ["| " + " | ".join(t for t, _, _ in columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(fmt.format(r[key]) for _, key, fmt in columns) + " |" for r in rows]
    with open(os.path.join(out, f"{name}.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def plots(results, pos, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    styles = {"lammps": ("k", "-"), "breccia": ("tab:blue", "--"), "matched": ("tab:red", ":"),
              "no-family": ("tab:green", "-."), "no-short-range": ("tab:orange", "-."),
              "before-force": ("tab:purple", "-.")}
    for model in sorted({r["model"] for r in results}):
        rules = [x for x in RULES if any(r["model"] == model and r["rule"] == x for r in results)]
        fig, axes = plt.subplots(3, len(rules), figsize=(5 * len(rules), 11), squeeze=False)
        for c, rule in enumerate(rules):
            for r in (r for r in results if r["model"] == model and r["rule"] == rule):
                color, ls = styles[r["variant"]]
                label = "LAMMPS" if r["code"] == "lammps" else f"Breccia ({r['variant']})"
                h = r["history"]
                axes[0, c].plot(h[:, 0] * 1e6, h[:, 1] * 1e3, color=color, ls=ls, label=label)
                axes[1, c].plot(h[:, 0] * 1e6, h[:, 2] / 1e3, color=color, ls=ls, label=label)
                y, d = axis_profile(pos, r["damage_count"])
                axes[2, c].plot(d, y * 1e3, color=color, ls=ls, marker="o", ms=3, label=label)
            axes[0, c].set(title=f"{model.upper()}, rule: {rule}", xlabel="time (us)", ylabel="kinetic energy (mJ)")
            axes[1, c].set(xlabel="time (us)", ylabel="force on the indenter (kN)")
            axes[2, c].set(xlabel="mean damage (LAMMPS measure), |r| <= 1.5 mm of the axis", ylabel="height y (mm)", xlim=(-0.02, 1.02))
            for a in axes[:, c]:
                a.grid(alpha=0.3)
                a.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"{model}.png"), dpi=90)
        plt.close(fig)


if __name__ == "__main__":
    main()
