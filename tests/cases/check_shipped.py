"""Run every shipped case file as shipped, or each of its variants, for a few steps.

    check_shipped.py (--shipped | --variants) --source ROOT --bin BIN_DIR --work DIR [--python PY] [--steps N]

--shipped : for each case file (every cases/*/*.yaml with a top-level model:, case*.yaml and the
            others the READMEs run: concrete-blast's ring files, the cask's knock files), writes its specimen into a fresh run folder with the
            commands its README gives (the tables below; a coarse spacing where the specimen
            takes one, to keep the test quick), then `breccia-solve CASE -o RUN --steps N`
            with no option that changes the file: the particle file is found in the output
            folder, so the shipped file must hold real values and name its own sets.
--variants: the same specimens, then `breccia-solve CASE -o RUN/NAME --variant NAME --steps N`
            for every entry of the file's `variants:` block (each applied as --set would be;
            RUN/NAME holds links to the specimen's files).
A case file missing from SPECIMENS fails the test, so that a new case cannot skip it.
Exit 0: every run finished; 1: a run failed (its output is printed).
"""
import argparse
import glob
import os
import shutil
import subprocess
import sys
import time

import yaml

# Specimen commands per shipped case file, as the case READMEs give them: {bin} the tools,
# {py} Python, {case} the case folder, {run} the run folder. Spacings are the coarsest that
# still give each specimen its sets and surfaces (a few steps test the file, not the physics).
PLACE = "{bin}/breccia-place"
SPECIMENS = {
    "concrete-blast/case.yaml": [
        "{bin}/breccia-mesh {case}/specimen-quick.yaml -o {run}/specimen.msh --threads 1",
        PLACE + " {run}/specimen.msh -o {run}/particles.h5 --require-groups concrete,charge_hole"],
    # The pressurised-hole ring (docs/benchmarks.md, "Pressurised hole"): 6,776 tets.
    "concrete-blast/ring.yaml": [
        "{bin}/breccia-mesh {case}/ring-specimen.yaml -o {run}/ring.msh --threads 1 --quiet",
        PLACE + " {run}/ring.msh -o {run}/particles.h5 --require-groups concrete,charge_hole"],
    "concrete-blast/ring-gas.yaml": [
        "{bin}/breccia-mesh {case}/ring-specimen.yaml -o {run}/ring.msh --threads 1 --quiet",
        PLACE + " {run}/ring.msh -o {run}/particles.h5 --require-groups concrete,charge_hole"],
    "dcb-energy/case.yaml": [
        "{py} {case}/specimen.py {run}/particles.h5 --spacing 1e-4 --length 8e-3 --arm-height 2e-3 --grip 0.5e-3"],
    "first-case/case.yaml": [
        "{bin}/breccia-mesh {case}/plate.step -o {run}/plate.msh --size '4 mm' --threads 1 --quiet",
        PLACE + " {run}/plate.msh -o {run}/particles.h5 --require-groups body,outer"],
    "fragmenting-cylinder/case.yaml": ["{py} {case}/specimen.py {run}/particles.h5 --spacing 0.0025"],
    "glass-branching/case-quick.yaml": [PLACE + " --lattice square --box 0,0,0.1,0.04 --spacing 0.0005 --thickness 1mm -o {run}/particles.h5"],
    "glass-branching/case-full.yaml": [PLACE + " --lattice square --box 0,0,0.1,0.04 --spacing 0.0005 --thickness 1mm -o {run}/particles.h5"],
    "glass-branching/case-3d-quick.yaml": [PLACE + " --lattice cubic --box 0,0,0,0.1,0.04,0.002 --spacing 0.001 -o {run}/particles.h5"],
    "glass-branching/case-3d.yaml": [PLACE + " --lattice cubic --box 0,0,0,0.1,0.04,0.002 --spacing 0.001 -o {run}/particles.h5"],
    "grady-ring/case.yaml": [
        "{py} {case}/specimen.py {run}/particles.h5 --radius 0.02 --width 0.0005 --spacing 0.0001 --thickness 0.001"],
    "granite-blast/case.yaml": [
        "{py} {case}/specimen.py {run}/particles.h5 --outer 0.036 --inner 0.0012875 --spacing 0.001 --thickness 0.001"],
    "homalite-branching/case.yaml": [PLACE + " --lattice square --box -0.002,-0.018,0.402,0.218 --spacing 0.004 --thickness 1mm -o {run}/particles.h5"],
    "inclusion-plate/case.yaml": ["{py} {case}/specimen.py {run}/particles.h5 --spacing 30e-6"],
    "kalthoff-winkler/case-quick.yaml": [PLACE + " --lattice square --box 0,0,0.1,0.2 --spacing 0.002 --thickness 9mm -o {run}/particles.h5"],
    "kalthoff-winkler/case-full.yaml": [PLACE + " --lattice square --box 0,0,0.1,0.2 --spacing 0.002 --thickness 9mm -o {run}/particles.h5"],
    "mps-cask-seismic/case.yaml": ["{py} {case}/record.py {run}/record.csv --pga 0.9 --duration 6 --seed 1995"],
    "mps-cask-seismic/knock.yaml": [],        # bodies in the case file, no record (its studies)
    "mps-cask-seismic/knock_pulse.yaml": [],
    "mps-fin-drop/case.yaml": [
        "{py} {case}/specimen.py {run}/particles.h5 --spacing 0.00375 --fin-length 0.2 --fin-thickness 0.015 "
        "--imperfection 0.1"],
    "mps-harmonics/case.yaml": [],  # a lattice in the case file
    "mps-ring-impact/case.yaml": [
        "{py} {case}/../grady-ring/specimen.py {run}/particles.h5 --radius 0.025 --width 0.005 --spacing 0.0005 --thickness 0.005"],
    "mps-rubber-rings/case.yaml": [],  # bodies in the case file
    "mps-taylor-bar/case.yaml": [],    # bodies in the case file
}


def run(cmd, log):
    """Runs cmd (a shell line); returns True on exit 0, else prints its output."""
    p = subprocess.run(cmd, shell=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    log.append(f"$ {cmd}\n{p.stdout}")
    return p.returncode == 0


def main():
    ap = argparse.ArgumentParser()
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--shipped", action="store_true")
    mode.add_argument("--variants", action="store_true")
    ap.add_argument("--source", required=True)
    ap.add_argument("--bin", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--python", default="/usr/bin/python3")
    ap.add_argument("--steps", type=int, default=2)
    a = ap.parse_args()
    cases_dir = os.path.join(a.source, "cases")
    # Every case file: a YAML of a case folder with a top-level model: (the specimen files of the
    # mesher have none). Named case*.yaml or not: the READMEs run ring.yaml and knock.yaml too.
    def is_case(path):
        with open(path) as fh:
            doc = yaml.safe_load(fh)
        return isinstance(doc, dict) and "model" in doc
    shipped = sorted(os.path.relpath(p, cases_dir) for p in glob.glob(os.path.join(cases_dir, "*", "*.yaml")) if is_case(p))
    if not shipped:
        print(f"FAIL: no case file under {cases_dir}")
        return 1
    failures = []
    missing = [c for c in shipped if c not in SPECIMENS]
    for c in missing:
        print(f"FAIL cases/{c}: no specimen commands in check_shipped.py's SPECIMENS (a new case file?)")
    failures += missing
    start = time.time()
    for rel in shipped:
        if rel in missing:
            continue
        case_file = os.path.join(cases_dir, rel)
        with open(case_file) as fh:
            variants = (yaml.safe_load(fh) or {}).get("variants") or {}
        names = list(variants) if a.variants else [None]
        if not names:
            continue
        run_dir = os.path.join(a.work, rel.replace("/", "_").replace(".yaml", ""))
        shutil.rmtree(run_dir, ignore_errors=True)
        os.makedirs(run_dir)
        log = []
        fields = {"bin": a.bin, "py": a.python, "case": os.path.dirname(case_file), "run": run_dir}
        ok = all(run(c.format(**fields), log) for c in SPECIMENS[rel])
        for name in names:
            t0 = time.time()
            out = run_dir if name is None else os.path.join(run_dir, name)
            extra = ""
            if name is not None:
                # Each variant in a folder of its own, holding links to the specimen's files:
                # the relative paths of the case file are found there, as in the shipped run.
                os.makedirs(out)
                for f in ("particles.h5", "record.csv"):
                    if os.path.exists(os.path.join(run_dir, f)):
                        os.symlink(os.path.join(run_dir, f), os.path.join(out, f))
                extra = f" --variant {name}"
            this_ok = ok and run(f"{a.bin}/breccia-solve {case_file} -o {out} --steps {a.steps} --threads 2 --quiet"
                                 f" --backend cpu{extra}", log)
            this_ok = this_ok and os.path.exists(os.path.join(out, "summary.json"))
            label = f"cases/{rel}" + ("" if name is None else f" --variant {name}")
            print(("PASS " if this_ok else "FAIL ") + f"{label} ({time.time() - t0:.1f} s)")
            if not this_ok:
                failures.append(label)
                print("".join(log))
    print(f"{len(failures)} failed; {time.time() - start:.0f} s in all")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
