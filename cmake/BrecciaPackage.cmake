# `make package` (cpack -G DEB): breccia_<version>_<arch>.deb installing under /usr the layout
# of cmake/BrecciaInstall.cmake. Library dependencies come from dpkg-shlibdeps on the
# executables; the Python modules the installed scripts import are listed by hand.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME breccia)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "Breccia")
set(BRECCIA_PACKAGE_CONTACT "Breccia maintainers <breccia@localhost>" CACHE STRING
  "Maintainer field of the .deb (name <email>)")
set(CPACK_PACKAGE_CONTACT "${BRECCIA_PACKAGE_CONTACT}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "fracture and fragmentation by peridynamics and MPS: mesher, particles, solver, post-processing")
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "${CPACK_PACKAGE_DESCRIPTION_SUMMARY}
 Breccia takes a specimen (YAML) through a gmsh mesh and one particle per element to a
 peridynamics (PMB, LPS, correspondence, dual horizon) or MPS solid run on OpenMP, MPI or
 CUDA, and post-processes the result into crack surfaces, fragments and their size
 distributions. Ships the tools breccia-mesh, -place, -solve, -mps, -post, -plan and
 -atlas, the verification cases (breccia-run-case NAME VARIANT) and the documentation.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_STRIP_FILES ON)  # as Debian ships executables: no symbol tables
# python3-*: breccia-post's chart scripts and the cases' run.sh helpers (numpy, h5py,
# matplotlib); meshio (scripts/convert_mesh.py, two cases' specimen builders) and yaml (one
# case's report) are recommended; openmpi-bin gives mpirun for distributed runs.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3, python3-numpy, python3-h5py, python3-matplotlib")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-meshio, python3-yaml, openmpi-bin")
include(CPack)
