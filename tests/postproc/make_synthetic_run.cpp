// Writes a large synthetic run directory for timing breccia-post (not a test):
//   make_synthetic_run DIR [NX NY NZ]   (default 37 x 36 x 36 hexes = 287,712 tets)
// The block is cut by three planes (8 fragments) with a smooth displacement field, damage
// near the cuts, two outputs and a 4096-row history with one probe.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "breccia/common/cli.hpp"
#include "synthetic_run.hpp"

namespace bt = breccia::postproc::testing;

int main(int argc, char** argv) {
  std::string dir;
  std::vector<int> cells{37, 36, 36};
  CLI::App app{"make_synthetic_run: a large synthetic run directory for timing breccia-post (not a test).",
               "make_synthetic_run"};
  breccia::cli::configure(app, "Output: DIR/results.h5, particles.h5 and history.csv (one probe, 4096 rows).");
  app.add_option("DIR", dir, "the run directory to write")->required();
  app.add_option("CELLS", cells, "hexes per edge, 6 tets each (default 37 36 36)")
      ->type_name("NX NY NZ")
      ->expected(3)
      // All three or none: TakeLast, the tools' default, would accept fewer.
      ->multi_option_policy(CLI::MultiOptionPolicy::Throw)
      ->check(breccia::cli::whole_number(1, 1000));
  if (const auto code = breccia::cli::parse(app, argc, argv)) return *code;
  const int nx = cells[0], ny = cells[1], nz = cells[2];
  const double h = 1e-3;
  bt::SyntheticRun run;
  run.dir = dir;
  run.model = bt::structured_mesh(3, {nx, ny, nz}, h);
  run.horizon_m = 3.0 * std::cbrt(h * h * h / 6.0);  // three mean particle spacings
  const double cx = 0.5 * nx * h, cy = 0.5 * ny * h, cz = 0.5 * nz * h;
  auto cut = [&](const double* a, const double* b) {
    return (a[0] - cx) * (b[0] - cx) < 0 || (a[1] - cy) * (b[1] - cy) < 0 || (a[2] - cz) * (b[2] - cz) < 0;
  };
  const auto broken = bt::bonds_where(run.model, run.horizon_m, cut);
  const size_t n = run.model.size();
  bt::SyntheticOutput last{20000, 2e-5, {}, {}, {}, broken};
  for (size_t i = 0; i < n; ++i) {
    const double* x = &run.model.position_m[3 * i];
    const double sx = x[0] > cx ? 1 : -1, sy = x[1] > cy ? 1 : -1, sz = x[2] > cz ? 1 : -1;
    last.displacement_m.insert(last.displacement_m.end(), {1e-3 * sx + 1e-3 * (x[0] - cx), 1e-3 * sy, 1e-3 * sz});
    last.velocity_m_s.insert(last.velocity_m_s.end(), {10 * sx, 10 * sy, 10 * sz});
    const double dmin = std::min({std::abs(x[0] - cx), std::abs(x[1] - cy), std::abs(x[2] - cz)});
    last.damage.push_back(std::max(0.0, 1.0 - dmin / (3 * h)) * 0.6);
  }
  run.outputs.push_back({0, 0.0, {}, {}, {}, {}});
  run.outputs.push_back(last);
  bt::write_run(run);
  std::ofstream hist(run.dir / "history.csv");
  hist << "step,time_s,kinetic_J,strain_J,external_work_J,dissipated_J,total_J,max_damage,broken_bonds,probe_A_ux\n";
  for (int k = 0; k < 4096; ++k) {
    const double t = k * 5e-9, f = k / 4095.0;
    hist << k * 5 << ',' << t << ',' << f << ',' << 0.5 * f << ',' << 1.6 * f << ',' << 0.1 * f << ',' << 1.6 * f
         << ",0.6,0," << 1e-8 * std::sin(2 * std::numbers::pi * 2e6 * t) << '\n';
  }
  std::printf("%zu particles, %zu broken bonds written to %s\n", n, broken.size() / 2, dir.c_str());
  return 0;
}
