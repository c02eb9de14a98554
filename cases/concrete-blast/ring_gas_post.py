# The gas ring (ring-gas.yaml): per output, the closed-cavity and the applied gas pressure (history.csv),
# wetted particles, vent state, particles softening / broken, the farthest broken particle.
# usage: python3 ring_gas_post.py RUN
import sys, numpy as np, h5py, csv
if len(sys.argv) != 2:
    sys.stderr.write("usage: python3 ring_gas_post.py RUN\n")
    sys.exit(2)
f = h5py.File(sys.argv[1] + "/results.h5", "r")
h = list(csv.DictReader(open(sys.argv[1] + "/history.csv")))
ht = np.array([float(r["time_s"]) for r in h]); hp = np.array([float(r["gas_pressure_Pa"]) for r in h])
hw = np.array([int(r["gas_wetted_particles"]) for r in h]); hv = np.array([int(r["gas_vented"]) for r in h])
x = f["particles/position"][:]; r = np.hypot(x[:, 0], x[:, 1])
print("t_us closed_MPa gas_MPa wetted vented softened broken reach_mm")
for k in sorted(f["output"].keys()):
    t = f["output"][k].attrs["time_s"]; d = f["output"][k]["damage"][:]
    i = np.argmin(abs(ht - t)); br = d > 0.5
    print("%.0f %.2f %.2f %d %d %d %d %.0f" % (t * 1e6, 40 * t / 1e-3, hp[i] / 1e6, hw[i], hv[i], (d > 0.05).sum(), br.sum(), r[br].max() * 1e3 if br.any() else 0))
