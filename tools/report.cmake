# The paper report (`pidlab report`, issue 6): a library the tests use too.
add_library(pidlab_report STATIC ${CMAKE_CURRENT_LIST_DIR}/report.cc)
target_include_directories(pidlab_report PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(pidlab_report PUBLIC pidlab_tuner pidlab_plot)
target_link_libraries(pidlab PRIVATE pidlab_report)
target_compile_definitions(pidlab PRIVATE PIDLAB_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
