# The installed layout (`cmake --install build --prefix P`, and the .deb under /usr):
#   P/bin/breccia-{mesh,place,solve,mps,post,plan,atlas}, P/bin/breccia-run-case (scripts/run_case.sh)
#   P/share/breccia/cases/             every case folder, as in the source tree
#   P/share/breccia/scripts/           what the cases' run.sh call (case_env.sh) and convert_mesh.py
#   P/share/breccia/postproc/scripts/  breccia-post's chart scripts
#   P/share/breccia/plan/              breccia-plan's throughputs.yaml and atlas.csv
#   P/share/doc/breccia/               README.md and docs/
# The executables find share/breccia from their own location (common's data_dir.hpp), so the
# build tree gets the same share/breccia, made of links into the source tree: one lookup
# rule for both trees and no source path compiled into a binary.
include(GNUInstallDirs)
set(BRECCIA_DATA_SUBDIR ${CMAKE_INSTALL_DATADIR}/breccia)
set(BRECCIA_DOC_SUBDIR ${CMAKE_INSTALL_DATAROOTDIR}/doc/breccia)  # the package's name, as Debian has it

set(BRECCIA_INSTALLED_TOOLS breccia-mesh breccia-place breccia-solve breccia-mps breccia-post breccia-plan breccia-atlas)
foreach(tool IN LISTS BRECCIA_INSTALLED_TOOLS)
  if(TARGET ${tool})  # BRECCIA_STAGES may leave stages out
    install(TARGETS ${tool} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()
# One script for both trees: installed as bin/breccia-run-case it runs the installed cases
# with the tools beside it (scripts/run_case.sh says how it tells the two apart).
install(PROGRAMS scripts/run_case.sh DESTINATION ${CMAKE_INSTALL_BINDIR} RENAME breccia-run-case)

install(DIRECTORY cases/ DESTINATION ${BRECCIA_DATA_SUBDIR}/cases USE_SOURCE_PERMISSIONS
  PATTERN __pycache__ EXCLUDE PATTERN "*.pyc" EXCLUDE)
install(PROGRAMS scripts/case_env.sh scripts/convert_mesh.py
  DESTINATION ${BRECCIA_DATA_SUBDIR}/scripts)
install(DIRECTORY postproc/scripts/ DESTINATION ${BRECCIA_DATA_SUBDIR}/postproc/scripts
  USE_SOURCE_PERMISSIONS PATTERN __pycache__ EXCLUDE PATTERN "*.pyc" EXCLUDE)
install(FILES tools/plan/throughputs.yaml docs/atlas/atlas.csv DESTINATION ${BRECCIA_DATA_SUBDIR}/plan)
install(FILES README.md DESTINATION ${BRECCIA_DOC_SUBDIR})
install(DIRECTORY docs/ DESTINATION ${BRECCIA_DOC_SUBDIR})

# The build tree's share/breccia: the same relative paths, linked to the sources (edits to a
# case or a chart script take effect without a rebuild).
set(_build_data ${CMAKE_BINARY_DIR}/${BRECCIA_DATA_SUBDIR})
file(MAKE_DIRECTORY ${_build_data}/postproc ${_build_data}/plan)
foreach(pair IN ITEMS "cases|cases" "scripts|scripts" "postproc/scripts|postproc/scripts"
                      "tools/plan/throughputs.yaml|plan/throughputs.yaml" "docs/atlas/atlas.csv|plan/atlas.csv")
  string(REPLACE "|" ";" pair "${pair}")
  list(GET pair 0 from)
  list(GET pair 1 to)
  file(REMOVE ${_build_data}/${to})  # a link left by an earlier configure (REMOVE does not follow it)
  file(CREATE_LINK ${PROJECT_SOURCE_DIR}/${from} ${_build_data}/${to} SYMBOLIC)
endforeach()
