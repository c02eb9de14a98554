# Included from tests/solver/CMakeLists.txt: the planner's tests as their own executable,
# so their run-time budget (< 60 s) is separate from test_solver's.
if(TARGET breccia_plan AND TARGET breccia_atlas_measures AND TARGET breccia-solve AND EXISTS ${PROJECT_SOURCE_DIR}/tests/solver/test_plan.cpp)
  add_executable(test_plan ${PROJECT_SOURCE_DIR}/tests/solver/test_plan.cpp)
  target_link_libraries(test_plan PRIVATE Breccia::plan Breccia::cli breccia_atlas_measures GTest::gtest_main)
  target_compile_definitions(test_plan PRIVATE BRECCIA_PLAN_EXE="$<TARGET_FILE:breccia-plan>")
  add_dependencies(test_plan breccia-plan)
  gtest_discover_tests(test_plan DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 300 ENVIRONMENT ${BRECCIA_UNIT_TEST_ENV})
endif()
