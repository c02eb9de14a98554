# The pressurised-hole ring (docs/benchmarks.md, "Pressurised hole"), per output of the ramped run:
# pressure, particles softening (d > 0.05) and broken (d > 0.5), the farthest broken particle, the
# share of the outer face's particles broken, u_r / Lame near the hole and on the outer face.
# usage: python3 ring_post.py RUN/results.h5 PEAK_PA RAMP_TIME_S   (ring.yaml: 40e6 1e-3)
import sys, numpy as np, h5py
if len(sys.argv) != 4:
    sys.stderr.write("usage: python3 ring_post.py RUN/results.h5 PEAK_PA RAMP_TIME_S   (ring.yaml: 40e6 1e-3)\n")
    sys.exit(2)
f = h5py.File(sys.argv[1], "r"); pmax = float(sys.argv[2]); tramp = float(sys.argv[3])
E, nu, a, b = 34.2e9, 0.25, 0.01, 0.15
x = f["particles/position"][:]; r = np.hypot(x[:, 0], x[:, 1])
outer = r > b - 8e-3
g = f["output"]
print("t_us p_MPa softened(d>0.05) broken(d>0.5) reach_mm outer_broken_share mean_ur(r<40)/Lame soft_reach_mm(d>0.05) ur_outer/Lame")
for k in sorted(g.keys()):
    t = g[k].attrs["time_s"]; p = pmax * min(t / tramp, 1.0)
    d = g[k]["damage"][:]; u = g[k]["displacement"][:]
    ur = (u[:, 0] * x[:, 0] + u[:, 1] * x[:, 1]) / r
    lame = p * a * a / (E * (b * b - a * a)) * ((1 - nu) * r + (1 + nu) * b * b / r)
    m = (r > 12e-3) & (r < 40e-3) & (d < 0.05)
    br = d > 0.5
    reach = r[br].max() * 1e3 if br.any() else 0
    sr = r[d > 0.05].max() * 1e3 if (d > 0.05).any() else 0
    print("%.0f %.2f %d %d %.0f %.2f %.3f %.0f %.3f" % (t * 1e6, p / 1e6, (d > 0.05).sum(), br.sum(), reach, br[outer].mean(),
          ur[m].sum() / lame[m].sum() if p > 0 and m.any() else 0, sr, ur[outer].sum() / lame[outer].sum() if p > 0 else 0))
