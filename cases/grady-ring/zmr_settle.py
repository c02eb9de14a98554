"""When does a softening ring stop breaking? Fragment count and dissipation against time.

    zmr_settle.py [--window-us W] [--png OUT.png] RUN [RUN ...]

Each RUN is a run folder of run.sh written with outputs along the way (OUTPUT_EVERY) and
post-processed at every output (`breccia-post RUN --fragments --all`, which run.sh does when
OUTPUT_EVERY is set). Fragments are report.py's (connected pieces of the graph of bonds that are
not fully broken: a bond in softening still holds; kept: at least two particle columns long).

Zhou, Molinari & Ramesh's size is the final one, when every cohesive zone has either opened
fully or unloaded. Both show in a run: the kept-fragment count stops changing, and the energy
dissipated by softening bonds (history.csv `dissipated_J`, booked as a bond softens) stops
growing. **Settled** at the end of a run: over the last W microseconds (default 10) the kept
count changed by less than 2% and the dissipated energy grew by less than 0.5%. (The count
of a PD ring does not stop outright: long after the dissipation has stopped, the last bonds of
crack bands that opened early still break now and then, README "Runs to a settled count".)
Prints the time table of each run and writes RUN/settle.json.
"""
import argparse
import json
import os

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from report import kept_fragments, ring_geometry  # noqa: E402

DISSIPATION_TOLERANCE = 0.005  # relative growth of dissipated_J over the window
COUNT_TOLERANCE = 0.02  # relative change of the kept count over the window


def history_of(run):
    with h5py.File(os.path.join(run, "results.h5"), "r") as f:
        ring = ring_geometry(f["particles/position"][:, :2])
        thickness = float(f.attrs["thickness_m"])
        outputs = [(int(g.attrs["step"]), float(g.attrs["time_s"])) for g in f["output"].values()]
    outputs.sort()
    hist = np.genfromtxt(os.path.join(run, "history.csv"), delimiter=",", names=True)
    rows = []
    for step, t in outputs:
        csv = os.path.join(run, "post", f"fragments_{step:06d}.csv")
        if not os.path.exists(csv):
            continue
        _, count, kept, arc, _ = kept_fragments(csv, ring, thickness)
        # dissipated_J at the history row nearest this output (history_every divides output steps)
        k = int(np.argmin(np.abs(hist["step"] - step)))
        rows.append({"step": step, "time_us": t * 1e6, "fragments_all": int(len(count)),
                     "fragments_kept": int(kept.sum()),
                     "mean_size_mm": float(arc[kept].mean() * 1e3) if kept.any() else float("nan"),
                     "circumference_over_all_mm": float(2 * np.pi * ring["radius"] / len(count) * 1e3),
                     "dissipated_J": float(hist["dissipated_J"][k])})
    return rows


def verdict(rows, window_us):
    t_end = rows[-1]["time_us"]
    # From the last output at or before t_end - W: the window is covered whole.
    start = max([k for k, r in enumerate(rows) if r["time_us"] <= t_end - window_us + 1e-9] or [0])
    last = rows[start:]
    kept = [r["fragments_kept"] for r in last]
    count_change = (max(kept) - min(kept)) / max(kept)
    d0, d1 = last[0]["dissipated_J"], last[-1]["dissipated_J"]
    growth = (d1 - d0) / d1 if d1 > 0 else 0.0
    # The last time the kept count changed: the fragments' final count holds from there on.
    changed = [b["time_us"] for a, b in zip(rows, rows[1:]) if a["fragments_kept"] != b["fragments_kept"]]
    return {"window_us": window_us, "window_covered": t_end - last[0]["time_us"] >= window_us - 1e-6,
            "kept_count_change": count_change, "dissipation_growth": growth,
            "last_count_change_us": changed[-1] if changed else rows[0]["time_us"],
            "settled": bool(count_change < COUNT_TOLERANCE and growth < DISSIPATION_TOLERANCE and len(last) > 1 and
                            t_end - last[0]["time_us"] >= window_us - 1e-6)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--window-us", type=float, default=10.0)
    ap.add_argument("--png")
    a = ap.parse_args()
    fig, axs = plt.subplots(1, 2, figsize=(10, 4)) if a.png else (None, None)
    for run in a.runs:
        rows = history_of(run)
        if not rows:
            raise SystemExit(f"zmr_settle.py: {run}/post has no fragments_<step>.csv (breccia-post {run} --fragments --all)")
        v = verdict(rows, a.window_us)
        # The first output at which the rule already held (the run could have stopped there).
        first = next((rows[k] for k in range(1, len(rows))
                      if rows[k]["time_us"] >= a.window_us and verdict(rows[:k + 1], a.window_us)["settled"]), None)
        v["first_settled_us"] = first["time_us"] if first else None
        v["size_when_first_settled_mm"] = first["mean_size_mm"] if first else None
        with open(os.path.join(run, "settle.json"), "w") as fh:
            json.dump({"run": run, "verdict": v, "outputs": rows}, fh, indent=1)
        print(f"## {run}")
        print("| t (us) | kept | all | mean size (mm) | circumference / all (mm) | dissipated (mJ) |")
        print("|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['time_us']:.1f} | {r['fragments_kept']} | {r['fragments_all']} | {r['mean_size_mm']:.3f} | "
                  f"{r['circumference_over_all_mm']:.3f} | {r['dissipated_J'] * 1e3:.4f} |")
        print(f"settled: {v['settled']} (over the last {a.window_us:g} us: kept count change "
              f"{v['kept_count_change']:.1%}, dissipation growth {v['dissipation_growth']:.2%}, "
              f"last count change at {v['last_count_change_us']:.1f} us); first settled at "
              + (f"{v['first_settled_us']:.1f} us, mean size {v['size_when_first_settled_mm']:.3f} mm" if first else "-"))
        if a.png:
            t = [r["time_us"] for r in rows]
            axs[0].plot(t, [r["mean_size_mm"] for r in rows], "o-", ms=3, label=os.path.basename(run.rstrip("/")))
            d = np.array([r["dissipated_J"] for r in rows])
            axs[1].plot(t, d / d[-1], "o-", ms=3, label=os.path.basename(run.rstrip("/")))
    if a.png:
        axs[0].set_xlabel("time (us)")
        axs[0].set_ylabel("mean size of kept fragments (mm)")
        axs[1].set_xlabel("time (us)")
        axs[1].set_ylabel("dissipated energy / final")
        for ax in axs:
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
