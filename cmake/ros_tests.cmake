# Tests of the ROS layer: a plain gtest on the adapters (no master) and rostests that drive the
# nodes through their service, action and topics. Every test name is appended to
# AP_EXPECTED_TESTS (scripts/test checks one result file per name).
find_package(rostest REQUIRED)

catkin_add_gtest(test_ros_conversions test/ros/test_ros_conversions.cpp)
target_link_libraries(test_ros_conversions ${PROJECT_NAME}_ros gtest_main)
list(APPEND AP_EXPECTED_TESTS test_ros_conversions)
