# Tests of the Python module (test/python/): unittest modules run through catkin with the devel
# space sourced, each group writing one JUnit result file (test/python/run_unittest.py) that
# scripts/test counts. Included from CMakeLists.txt's test section.
#
# Not in the sanitizer builds (scripts/test --asan): an ASan-instrumented extension cannot be
# loaded into Debian's uninstrumented python3 ("ASan runtime does not come first") without
# preloading the runtime, and CPython's own allocations would then be reported as leaks. The
# module's C++ is the core's, which the sanitizer suite covers through its C++ tests.
if(CMAKE_CXX_FLAGS MATCHES "-fsanitize")
  message(STATUS "Python tests (test/python): not registered in a sanitizer build")
  return()
endif()
set(AP_PYTHON_TEST_DIR ${CMAKE_CURRENT_SOURCE_DIR}/test/python)
set(AP_PYTHON_RESULTS ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME})
foreach(name module batch)
  catkin_run_tests_target(python ${name} python-${name}.xml
    COMMAND "${PYTHON_EXECUTABLE} ${AP_PYTHON_TEST_DIR}/run_unittest.py --results ${AP_PYTHON_RESULTS}/python-${name}.xml ${AP_PYTHON_TEST_DIR}/test_${name}.py"
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
    DEPENDENCIES _core plan_maneuver)
  list(APPEND AP_EXPECTED_TESTS python_${name})
endforeach()
