# Tests of the Python module (test/python/): unittest modules run through catkin with the devel
# space sourced, each group writing one JUnit result file (test/python/run_unittest.py) that
# scripts/test counts. Included from CMakeLists.txt's test section.
set(AP_PYTHON_TEST_DIR ${CMAKE_CURRENT_SOURCE_DIR}/test/python)
set(AP_PYTHON_RESULTS ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME})
foreach(name module batch)
  catkin_run_tests_target(python ${name} python-${name}.xml
    COMMAND "${PYTHON_EXECUTABLE} ${AP_PYTHON_TEST_DIR}/run_unittest.py --results ${AP_PYTHON_RESULTS}/python-${name}.xml ${AP_PYTHON_TEST_DIR}/test_${name}.py"
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
    DEPENDENCIES _core plan_maneuver)
  list(APPEND AP_EXPECTED_TESTS python_${name})
endforeach()
