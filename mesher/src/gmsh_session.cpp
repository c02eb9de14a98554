#include "gmsh_session.hpp"

#include <gmsh.h>

#include <vector>

namespace breccia::mesher {

GmshSession::GmshSession(int threads) {
  gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("General.Verbosity", 5);  // keep everything in the log, print nothing
  gmsh::logger::start();
  gmsh::option::setNumber("General.NumThreads", threads);
  gmsh::option::setNumber("Mesh.MaxNumThreads1D", threads);
  gmsh::option::setNumber("Mesh.MaxNumThreads2D", threads);
  gmsh::option::setNumber("Mesh.MaxNumThreads3D", threads);
}

GmshSession::~GmshSession() {
  gmsh::logger::stop();
  gmsh::finalize();
}

std::string GmshSession::errors() const {
  std::vector<std::string> log;
  gmsh::logger::get(log);
  std::string errors, warnings;
  for (const auto& line : log) {
    if (line.rfind("Error", 0) == 0) errors += (errors.empty() ? "" : "; ") + line;
    else if (line.rfind("Warning", 0) == 0 && warnings.size() < 400) warnings += (warnings.empty() ? "" : "; ") + line;
  }
  return errors.empty() ? warnings : errors;
}

}  // namespace breccia::mesher
