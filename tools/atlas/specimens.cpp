#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "atlas.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/solver/case_config.hpp"

namespace breccia::atlas {
namespace {

std::string box_list(int dimension, const double lo[3], const double hi[3]) {
  std::string s = "[";
  for (int k = 0; k < dimension; ++k) s += num(lo[k]) + ", ";
  for (int k = 0; k < dimension; ++k) s += num(hi[k]) + (k + 1 < dimension ? ", " : "]");
  return s;
}

}  // namespace

double seconds_since(const std::chrono::steady_clock::time_point& t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

CsvTable::CsvTable(std::string path, std::string header, bool keep_existing) : path_(std::move(path)) {
  if (keep_existing && std::filesystem::exists(path_)) {
    std::ifstream in(path_);
    std::ostringstream all;
    all << in.rdbuf();
    content_ = all.str();
    const std::string first = content_.substr(0, content_.find('\n'));
    if (first != header)
      throw InputError(path_, "header", "'" + first + "'", "'" + header + "' (the atlas CSV contract)");
  } else {
    content_ = header + "\n";
  }
  if (!std::filesystem::path(path_).parent_path().empty())
    std::filesystem::create_directories(std::filesystem::path(path_).parent_path());
  write_text_file(path_ + ".partial", content_);
}

void CsvTable::add(const std::string& line) {
  content_ += line + "\n";
  write_text_file(path_ + ".partial", content_);
}

void CsvTable::commit() { std::filesystem::rename(path_ + ".partial", path_); }

std::string csv_line(const AtlasRow& r) {
  std::ostringstream o;
  o << r.problem << "," << r.model << "," << r.dimension << "," << r.particles_kind << "," << num(r.m) << ","
    << num(r.spacing_m) << "," << r.precision << "," << r.backend << "," << r.threads << "," << r.particles << "," << r.bonds << "," << r.steps
    << "," << num(r.wall_s) << "," << num(r.error) << "," << r.error_measure;
  return o.str();
}

solver::PdSystem system_from_yaml(const std::string& work_dir, const std::string& name, const std::string& yaml) {
  std::filesystem::create_directories(work_dir);
  const std::string path = work_dir + "/" + name + ".yaml";
  std::ofstream(path) << yaml;
  return solver::setup_system(solver::parse_case_file(path));
}

std::string SpecimenMaker::tet_particles(int dimension, const double lo[3], const double hi[3], double spacing_m,
                                         double thickness_m) {
  // Mesh size from the target particle spacing: a particle's spacing is the cube (square)
  // root of its cell, 0.49 (3D, regular tet: (1/(6 sqrt 2))^(1/3)) or 0.66 (2D, equilateral
  // triangle: (sqrt 3 / 4)^(1/2)) times the element edge.
  const double mesh_size = spacing_m / (dimension == 3 ? 0.49 : 0.66);
  std::string key = "tet" + std::to_string(dimension) + "d";
  for (int k = 0; k < dimension; ++k) key.append("_").append(num((hi[k] - lo[k]) * 1e3));
  key.append("_h").append(num(mesh_size * 1e6));
  const std::string dir = work_dir + "/specimens/" + key;
  const std::string particles = dir + "/particles.h5";
  if (std::filesystem::exists(particles)) return particles;
  std::filesystem::create_directories(dir);
  std::ofstream spec(dir + "/specimen.yaml");
  spec << "dimension: " << dimension << "\n";
  if (dimension == 3)
    spec << "body: {shape: box, name: solid, origin: [" << num(lo[0]) << ", " << num(lo[1]) << ", " << num(lo[2])
         << "], size: [" << num(hi[0] - lo[0]) << ", " << num(hi[1] - lo[1]) << ", " << num(hi[2] - lo[2]) << "]}\n";
  else
    spec << "body: {shape: rectangle, name: solid, origin: [" << num(lo[0]) << ", " << num(lo[1])
         << "], size: [" << num(hi[0] - lo[0]) << ", " << num(hi[1] - lo[1]) << "]}\n";
  spec << "mesh: {size: " << num(mesh_size) << "}\n";
  spec.close();
  std::string cmd = mesh_exe + " " + dir + "/specimen.yaml -o " + dir + "/specimen.msh --quiet > " + dir +
                    "/mesh.log 2>&1 && " + place_exe + " " + dir + "/specimen.msh -o " + particles +
                    (dimension == 2 ? " --thickness " + num(thickness_m) : std::string()) + " > " + dir +
                    "/place.log 2>&1";
  if (verbose) std::fprintf(stderr, "[atlas] meshing %s\n", key.c_str());
  if (std::system(cmd.c_str()) != 0)
    throw InputError(dir + "/mesh.log", "breccia-mesh/breccia-place", "failed: " + cmd,
                     "working --mesh-exe and --place-exe");
  return particles;
}

std::string SpecimenMaker::specimen_yaml(const Settings& s, int dimension, const double lo[3], const double hi[3],
                                         double thickness_m) {
  if (s.kind == "tet")
    return "specimen: {particles: " + tet_particles(dimension, lo, hi, s.spacing_m, thickness_m) + "}\n";
  return "specimen: {lattice: {dimension: " + std::to_string(dimension) + ", box: " + box_list(dimension, lo, hi) +
         ", spacing: " + num(s.spacing_m) + (dimension == 2 ? ", thickness: " + num(thickness_m) : std::string()) +
         "}}\n";
}

}  // namespace breccia::atlas
