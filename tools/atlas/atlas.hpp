#pragma once
// breccia-atlas: sweeps of the PD solver over problems with known answers (speed against
// accuracy) and the measured stability map. docs/atlas.md explains every measure; the CSV
// columns are a contract read by breccia-plan (docs/atlas/atlas.csv).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "breccia/common/csv.hpp"
#include "breccia/solver/pd_system.hpp"
#include "measures.hpp"

namespace breccia::atlas {

// One point of a sweep: what the solver was asked to do.
struct Settings {
  std::string model = "pmb";         // pmb | lps
  std::string kind = "lattice";      // lattice | tet (tet-centroid; triangle-centroid in 2D)
  double m = 3.0;                    // nominal horizon / spacing
  double spacing_m = 1e-3;           // target particle spacing
  std::string precision = "float64"; // float64 | float32 (model.precision)
  std::string backend = "cpu";       // cpu | cuda (time-stepping problems only)
};

// One row of docs/atlas/atlas.csv (header: kAtlasHeader).
struct AtlasRow {
  std::string problem, model;
  int dimension = 3;
  std::string particles_kind;
  double m = 0.0, spacing_m = 0.0;
  std::string precision = "float64";
  std::string backend = "cpu";
  int threads = 1;
  size_t particles = 0, bonds = 0;
  long long steps = 0;
  double wall_s = 0.0, error = 0.0;
  std::string error_measure;
};

inline constexpr const char* kAtlasHeader =
    "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,error,"
    "error_measure";

// Appends rows to a CSV, rewriting the whole file atomically after each row, so an
// interrupted sweep leaves every finished row and never a half-written line.
// A table written row by row to PATH.partial (each row kept as it comes: a long sweep's
// progress), which commit() moves onto PATH. An interrupted or failed sweep leaves PATH as it
// was: the shipped docs/atlas/*.csv, which the planner reads, is replaced only by a whole table.
class CsvTable {
public:
  CsvTable(std::string path, std::string header, bool keep_existing);
  void add(const std::string& line);
  void commit();

private:
  std::string path_, content_;
};

std::string csv_line(const AtlasRow& r);

// Where particle files come from: the lattice is built by the solver itself; tet-centroid
// particles come from breccia-mesh + breccia-place, cached under work_dir.
struct SpecimenMaker {
  std::string work_dir;
  std::string mesh_exe, place_exe;
  bool verbose = true;
  // A box [lo, hi] (2D: z ignored) as the `specimen:` YAML block for the given settings.
  std::string specimen_yaml(const Settings& s, int dimension, const double lo[3], const double hi[3],
                            double thickness_m = 1e-3);
  // Path of tet (triangle) centroid particles of the box with the given target spacing.
  std::string tet_particles(int dimension, const double lo[3], const double hi[3], double spacing_m,
                            double thickness_m);
};

// Builds a system from YAML text (written to work_dir/<name>.yaml).
solver::PdSystem system_from_yaml(const std::string& work_dir, const std::string& name, const std::string& yaml);

// Horizon factor handed to the solver for a nominal m: the lattice tests' 3.015 rule, so
// a lattice point at exactly m spacings is inside.
inline double horizon_factor(double m) { return m + 0.015; }

// A number for the YAML the sweeps write, to 9 significant digits.
inline std::string num(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

// A run's message as a CSV field, with the working folder's prefix cut from the paths it
// names: the sweeps' work folder is made absolute (the mesher runs as a subprocess), and the
// committed tables should not carry the path of the machine that made them.
inline std::string message_field(std::string message) {
  const std::string here = std::filesystem::current_path().string() + "/";
  for (size_t at = message.find(here); at != std::string::npos; at = message.find(here, at))
    message.erase(at, here.size());
  return csv_plain_field(std::move(message));
}

using RowSink = std::function<void(const AtlasRow&)>;

struct SweepPlan {
  bool quick = false;
  std::vector<std::string> problems, models, kinds;
  std::vector<double> m_values{2, 3, 4, 5};
  // float32 rows for the problems whose error float could change (wave speed, strain
  // energy, quasi-static bar): --precisions float64,float32.
  std::vector<std::string> precisions{"float64"};
  // --backends cpu,cuda: the time-stepping problems (wave speed bar, Kalthoff-Winkler) run on
  // each; the static, ADR and MPS problems and the stability studies stay on the CPU.
  std::vector<std::string> backends{"cpu"};
  BackendFactory cuda_backend;  // set by main when the build has the CUDA backend
  // Grading ratios of the graded study (--gradings); empty: its default list.
  std::vector<double> gradings;
  int threads = 1;
};

void wave_speed_bar(const SweepPlan& plan, SpecimenMaker& maker, const RowSink& sink);
void static_calibration(const SweepPlan& plan, SpecimenMaker& maker, const RowSink& sink);  // strain + fracture energy
void quasi_static_bar(const SweepPlan& plan, SpecimenMaker& maker, const RowSink& sink);
void kalthoff_winkler(const SweepPlan& plan, SpecimenMaker& maker, const RowSink& sink);
void softening_strength(const SweepPlan& plan, SpecimenMaker& maker, const RowSink& sink);

// Stability map: docs/atlas/stability.csv, one row per run.
inline constexpr const char* kStabilityHeader =
    "study,model,dimension,particles_kind,m,dt_factor,particles,bonds,min_family,steps,status,detected_by,"
    "energy_ratio,energy_scatter,message";
// series_csv: where the correspondence rows' time series go (beside the table).
void stability_map(const SweepPlan& plan, SpecimenMaker& maker, CsvTable& table, const std::string& series_csv);

// Graded particle arrangements with and without dual horizon: docs/atlas/stability_graded.csv.
inline constexpr const char* kGradedHeader =
    "model,grading,dual_horizon,particles,bonds,min_family,min_local_m,coarse_energy_error,fine_energy_error,"
    "ghost_force,net_force,reflected_energy,steps,status,detected_by,energy_ratio,message";
void graded_stability(const SweepPlan& plan, SpecimenMaker& maker, CsvTable& table);

// MPS (stress-based solid) rows: mps_wave_speed, thick_cylinder, thick_cylinder_hill
// (mps_atlas.cpp), and the MPS stability map in tension: docs/atlas/stability_mps.csv.
void mps_problems(const SweepPlan& plan, const RowSink& sink);
inline constexpr const char* kMpsStabilityHeader =
    "ramp_transits,pressure_force,hourglass,strain,particles,bonds,steps,min_neighbour_ratio,max_speed_ratio,status,detected_by,message";
void mps_tension_stability(const SweepPlan& plan, CsvTable& table);

// Elapsed seconds since a steady-clock start.
double seconds_since(const std::chrono::steady_clock::time_point& t0);

}  // namespace breccia::atlas
