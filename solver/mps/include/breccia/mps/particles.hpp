#pragma once
// The particles of an MPS case (a lattice from the case file, or particles.h5) and the
// prescribed-displacement sets selected on them. Shared by the displacement solver
// (simulation.hpp) and the stress-based solid (solid.hpp).
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/neighbours.hpp"

namespace breccia::mps {

struct ParticleCloud {
  int dimension = 2;
  double spacing_m = 0.0;
  double thickness_m = 1.0;  // 2D out-of-plane thickness
  Periodicity periodic;
  std::vector<double> position_m;  // 3N, reference configuration
  std::vector<double> volume_m3;
  std::string content_id;          // "" for a lattice
  std::vector<std::string> set_names;
  std::vector<std::vector<int64_t>> set_members;
  std::vector<int> body_id;        // per particle for specimen.bodies (bodies.hpp); empty: one body
};

// Lattice (x fastest, then y, then z) or particle file; throws InputError for a spacing
// larger than the box or a periodic length below 2 re.
ParticleCloud build_particle_cloud(const CaseSpec& spec);

// Appends one particle at the centre of each cell of a square (2D, z = 0) or cubic lattice of
// count cells from the corner low_m, x fastest, then y, then z, each with the cell's volume
// (2D: spacing^2 x thickness), and returns how many it appended. keep (x, y, z), when given,
// cuts the lattice to a shape. Shared by specimen.lattice and the bodies' box and cylinder.
size_t append_lattice(int dimension, const std::array<double, 3>& low_m, const std::array<long long, 3>& count,
                      double spacing_m, double thickness_m, ParticleCloud& cloud,
                      const std::function<bool(double, double, double)>& keep = {});

// Particles whose displacement components follow a history (or stay zero).
struct PrescribedSet {
  std::vector<int> particles;
  std::array<bool, 3> components{};
  std::optional<BurstHistory> burst;
};

// One set per boundary entry of the case; throws InputError for an unknown set name or an
// entry that selects no particle.
std::vector<PrescribedSet> select_boundary(const CaseSpec& spec, const ParticleCloud& cloud);

// Index of the particle nearest to p (position_m: 3N reference positions); -1 if none.
int nearest_particle(const std::vector<double>& position_m, const std::array<double, 3>& p);

// Symplectic Euler (the paper's eqs 7-8) on components 0..dimension-1:
// v += dt a(u^k), then u += dt v^{k+1}. Shared by the linear and the stress solver.
void symplectic_euler_update(std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& v,
                             const std::array<std::vector<double>, 3>& a, int dimension, double dt);

// Every set's prescribed displacement and velocity at time t (both solvers' apply_prescribed).
void apply_prescribed_sets(const std::vector<PrescribedSet>& sets, double t, std::array<std::vector<double>, 3>& u,
                           std::array<std::vector<double>, 3>& v);

double burst_displacement(const BurstHistory& h, double t);
double burst_velocity(const BurstHistory& h, double t);

}  // namespace breccia::mps
