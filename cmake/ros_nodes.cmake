# ROS adapters: a library with the msg <-> Eigen conversions and the node classes, and one thin
# main per node. Included from CMakeLists.txt after the core library is defined.

set(AP_ROS_SOURCES
  src/ros/conversions.cpp
  src/ros/diagnostics.cpp
  src/ros/markers.cpp
  src/ros/planner_node.cpp
  src/ros/plant_node.cpp
  src/ros/tracker_node.cpp)

add_library(${PROJECT_NAME}_ros ${AP_ROS_SOURCES})
target_include_directories(${PROJECT_NAME}_ros PUBLIC include ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_ros PUBLIC ${PROJECT_NAME}_core ${catkin_LIBRARIES})
add_dependencies(${PROJECT_NAME}_ros ${${PROJECT_NAME}_EXPORTED_TARGETS} ${catkin_EXPORTED_TARGETS})

foreach(node attitude_planner_node attitude_tracker_node attitude_plant_node)
  add_executable(${node} src/ros/${node}.cpp)
  target_link_libraries(${node} ${PROJECT_NAME}_ros)
  install(TARGETS ${node} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endforeach()

install(TARGETS ${PROJECT_NAME}_ros
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
