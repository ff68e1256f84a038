# Tests of the package as others use it (test/packaging/): Python drivers run through catkin like
# any test, each writing one JUnit result file. Included from CMakeLists.txt's test section.
set(AP_PACKAGING_DIR ${CMAKE_CURRENT_SOURCE_DIR}/test/packaging)
set(AP_PACKAGING_RESULTS ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME})

# What `rosrun attitude_planner <TAB>` offers: exactly the nodes and the installed tools (plus
# the scripts/ entry points of the source tree); no find loop; replay.launch sets no global
# parameter.
set(AP_ROSRUN_EXECUTABLES attitude_planner_node attitude_tracker_node attitude_plant_node)
foreach(tool_source ${AP_TOOL_SOURCES})
  get_filename_component(tool_name ${tool_source} NAME_WE)
  list(APPEND AP_ROSRUN_EXECUTABLES ${tool_name})
endforeach()
# (catkin's run_tests.py runs each COMMAND argument as one shell command line: one string each.)
# plan_batch is a Python tool (catkin_install_python): offered, but not a build target.
string(REPLACE ";" " " AP_ROSRUN_EXECUTABLES_TEXT "${AP_ROSRUN_EXECUTABLES};plan_batch")
catkin_run_tests_target(packaging rosrun_offers packaging-rosrun_offers.xml
  COMMAND "${PYTHON_EXECUTABLE} ${AP_PACKAGING_DIR}/rosrun_offers.py --results ${AP_PACKAGING_RESULTS}/packaging-rosrun_offers.xml --expect ${AP_ROSRUN_EXECUTABLES_TEXT}"
  DEPENDENCIES ${AP_ROSRUN_EXECUTABLES})
list(APPEND AP_EXPECTED_TESTS packaging_rosrun_offers)

# A downstream catkin package (test/packaging/attitude_planner_client) built on this devel space
# as a user would: C++ linking the exported libraries, Python importing the srv and the action.
# It is compiled with this build's flags (the sanitizer builds need their runtime in the client).
set(AP_DOWNSTREAM_CMAKE_ARGS "'--cmake-arg=-DCMAKE_BUILD_TYPE=${CMAKE_BUILD_TYPE}'")
foreach(flags CMAKE_CXX_FLAGS CMAKE_EXE_LINKER_FLAGS)
  if(${flags})
    string(APPEND AP_DOWNSTREAM_CMAKE_ARGS " '--cmake-arg=-D${flags}=${${flags}}'")
  endif()
endforeach()
catkin_run_tests_target(packaging downstream_build packaging-downstream_build.xml
  COMMAND "${PYTHON_EXECUTABLE} ${AP_PACKAGING_DIR}/downstream_build.py --devel ${CATKIN_DEVEL_PREFIX} --work ${PROJECT_BINARY_DIR}/downstream_ws --results ${AP_PACKAGING_RESULTS}/packaging-downstream_build.xml ${AP_DOWNSTREAM_CMAKE_ARGS}"
  DEPENDENCIES ${PROJECT_NAME}_core ${PROJECT_NAME}_ros)
list(APPEND AP_EXPECTED_TESTS packaging_downstream_build)
