#pragma once
// One gmsh session per meshing call. gmsh keeps global state, so the session owns
// initialize/finalize; its terminal output is switched off and its messages are logged,
// so that a gmsh failure becomes one of our messages instead of a wall of text.
#include <string>

namespace breccia::mesher {

class GmshSession {
public:
  explicit GmshSession(int threads);
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  // gmsh's error (and, failing that, warning) messages since the session started, one line.
  std::string errors() const;
};

}  // namespace breccia::mesher
