include(${CMAKE_CURRENT_SOURCE_DIR}/report.cmake OPTIONAL)  # pidlab report (issue 6)
target_link_libraries(pidlab PRIVATE pidlab_lcm)  # pidlab launch, evaluate --backend lcm (issue 3)
