# Tests of the ROS layer: a plain gtest on the adapters (no master) and rostests that drive the
# nodes through their service, action and topics. Every test name is appended to
# AP_EXPECTED_TESTS (scripts/test checks one result file per name).
find_package(rostest REQUIRED)

catkin_add_gtest(test_ros_conversions test/ros/test_ros_conversions.cpp)
target_link_libraries(test_ros_conversions ${PROJECT_NAME}_ros gtest_main)
target_compile_definitions(test_ros_conversions PRIVATE AP_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
list(APPEND AP_EXPECTED_TESTS test_ros_conversions)
# The planner node's memory after stopped solves, in a process of its own (as the node is).
catkin_add_gtest(test_planner_memory test/ros/test_planner_memory.cpp)
target_link_libraries(test_planner_memory ${PROJECT_NAME}_ros gtest_main)
list(APPEND AP_EXPECTED_TESTS test_planner_memory)

# rostest gtests: each launches the node(s) under test and a gtest client, which roslaunch finds
# by package and type in devel/share/attitude_planner/test_nodes (not offered by rosrun).
set(CMAKE_RUNTIME_OUTPUT_DIRECTORY ${AP_ROSTEST_BIN_DIR})
foreach(name planner_service planner_action tracker tracker_sim_time)
  add_rostest_gtest(test_${name} test/ros/${name}.test test/ros/test_${name}.cpp)
  target_link_libraries(test_${name} ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
  add_dependencies(test_${name} attitude_planner_node attitude_tracker_node)
  list(APPEND AP_EXPECTED_TESTS test_${name})
endforeach()

# The tracker planning a scene at start-up: through the service, and in-process (same checks).
add_rostest_gtest(test_tracker_scene test/ros/tracker_scene_service.test test/ros/test_tracker_scene.cpp)
target_link_libraries(test_tracker_scene ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_scene attitude_planner_node attitude_tracker_node)
add_rostest(test/ros/tracker_scene_in_process.test DEPENDENCIES test_tracker_scene)
add_rostest(test/ros/tracker_scene_second_order.test DEPENDENCIES test_tracker_scene)
add_rostest(test/ros/tracker_scene_fourth_order.test DEPENDENCIES test_tracker_scene)
add_rostest(test/ros/tracker_scene_pointing.test DEPENDENCIES test_tracker_scene)
list(APPEND AP_EXPECTED_TESTS test_tracker_scene tracker_scene_in_process
     tracker_scene_second_order tracker_scene_fourth_order tracker_scene_pointing)

# The tracker drawing a scene's pointing constraints (and planning it with them via the service).
add_rostest_gtest(test_tracker_constraints test/ros/tracker_constraints.test
                  test/ros/test_tracker_constraints.cpp)
target_link_libraries(test_tracker_constraints ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_constraints attitude_planner_node attitude_tracker_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_constraints)

# Seed 001's drift + two-input system: the second service, and the tracker replaying a drift
# scene planned through it.
foreach(name planner_drift_service tracker_drift_scene)
  add_rostest_gtest(test_${name} test/ros/${name}.test test/ros/test_${name}.cpp)
  target_link_libraries(test_${name} ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
  add_dependencies(test_${name} attitude_planner_node attitude_tracker_node)
  list(APPEND AP_EXPECTED_TESTS test_${name})
endforeach()

# rostest with the stock checkers (advertisetest, publishtest) on the whole demo pipeline.
add_rostest(test/ros/demo_pipeline.test)
list(APPEND AP_EXPECTED_TESTS demo_pipeline)

# Scenes with effects: planned through the service, replayed under the scene's own effects (lands)
# and under ~replay_scene's (torque noise: misses); actuator limits planned and saturated.
add_rostest_gtest(test_tracker_effects test/ros/tracker_effects_planned.test
                  test/ros/test_tracker_effects.cpp)
target_link_libraries(test_tracker_effects ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_effects attitude_planner_node attitude_tracker_node)
add_rostest(test/ros/tracker_effects_unplanned.test DEPENDENCIES test_tracker_effects)
add_rostest(test/ros/tracker_effects_limited.test DEPENDENCIES test_tracker_effects)
list(APPEND AP_EXPECTED_TESTS test_tracker_effects tracker_effects_unplanned
     tracker_effects_limited)

# The tracker: the message honoured and streamed at ~rate (tracker_stream), marker
# bandwidth linear in the samples (tracker_bandwidth), closed loop against open loop under the
# disturbed scene (tracker_feedback: two trackers in their own namespaces).
foreach(name tracker_stream tracker_bandwidth tracker_feedback)
  add_rostest_gtest(test_${name} test/ros/${name}.test test/ros/test_${name}.cpp)
  target_link_libraries(test_${name} ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
  add_dependencies(test_${name} attitude_tracker_node)
  list(APPEND AP_EXPECTED_TESTS test_${name})
endforeach()

# ~mode replan: re-plans through the planner node's service without stalling the stream, lands as
# the law alone does; a failed re-plan keeps the plan in force.
add_rostest_gtest(test_tracker_replan test/ros/tracker_replan.test test/ros/test_tracker_replan.cpp)
target_link_libraries(test_tracker_replan ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_replan attitude_planner_node attitude_tracker_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_replan)

# Constraint health: re-plans under active torque limits none failed and no worse than the law
# alone, a start just inside a keep-out cone projected onto it, `done`'s worst violations against
# the published path.
add_rostest_gtest(test_tracker_constraint_health test/ros/tracker_constraint_health.test
                  test/ros/test_tracker_constraint_health.cpp)
target_link_libraries(test_tracker_constraint_health ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_constraint_health attitude_tracker_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_constraint_health)

# ~plant external: the law on the measured state of attitude_plant_node (odometry in,
# torque_command out) lands as the internal feedback mode does; no measurement: zero commands and
# a failed done, the stream at its rate.
add_rostest_gtest(test_tracker_external test/ros/tracker_external.test
                  test/ros/test_tracker_external.cpp)
target_link_libraries(test_tracker_external ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_external attitude_tracker_node attitude_plant_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_external)
# The same binary (TrackerPlantLoop.*): tracker.launch's plant:=node (attitude_plant_node started
# by the launch, the loop over topics) against its plant:=internal (the in-process body).
add_rostest(test/ros/tracker_plant_loop.test DEPENDENCIES test_tracker_external)

# A new maneuver mid-run: with a planner that never answers (hung_planner_node) the
# stream keeps its rate and both runs get `done`; the body is flown on from its state (no jump).
add_executable(hung_planner_node EXCLUDE_FROM_ALL test/ros/hung_planner_node.cpp)
target_link_libraries(hung_planner_node ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_rostest_gtest(test_tracker_takeover test/ros/tracker_takeover.test
                  test/ros/test_tracker_takeover.cpp)
target_link_libraries(test_tracker_takeover ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_takeover attitude_tracker_node hung_planner_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_takeover)

# Start-up parameter checks: a bad private parameter stops each node with a named error (exit
# 78); scene paths relative to the caller or package://; /use_sim_time through a remap (as
# replay.launch gives it to rviz) and the tracker's one warning while /clock is silent.
add_rostest_gtest(test_node_parameters test/ros/node_parameters.test
                  test/ros/test_node_parameters.cpp)
target_link_libraries(test_node_parameters gtest_main)  # no ROS client code: it runs the nodes
target_compile_definitions(test_node_parameters PRIVATE AP_TOOL_DIR="${AP_TOOL_DIR}/"
                           AP_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
add_dependencies(test_node_parameters attitude_planner_node attitude_tracker_node
                 attitude_plant_node)
list(APPEND AP_EXPECTED_TESTS test_node_parameters)

# The tracker flying a reaction-wheel scene (planned through the service) with its wheel torques
# through body + wheels; a feedback-mode tracker refusing it by name.
add_rostest_gtest(test_tracker_wheels test/ros/tracker_wheels.test test/ros/test_tracker_wheels.cpp)
target_link_libraries(test_tracker_wheels ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_wheels attitude_planner_node attitude_tracker_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_wheels)

# ~plant external with reaction wheels: the law through the wheels on attitude_plant_node's body +
# wheels (odometry and wheel_measurement in, wheel_command out) lands as the internal loop does;
# without spin inertias the mode is refused by name.
add_rostest_gtest(test_tracker_external_wheels test/ros/tracker_external_wheels.test
                  test/ros/test_tracker_external_wheels.cpp)
target_link_libraries(test_tracker_external_wheels ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(test_tracker_external_wheels attitude_tracker_node attitude_plant_node)
list(APPEND AP_EXPECTED_TESTS test_tracker_external_wheels)
# The same binary (TrackerWheelsLoop.*): wheels under a disturbance the plan never saw, on
# attitude_plant_node and on the tracker's own body + wheels, and internal replan with wheels.
add_rostest(test/ros/tracker_wheels_loop.test DEPENDENCIES test_tracker_external_wheels)
