# Tests of logs, replay and plots (issue 5). Included by tests/CMakeLists.txt.
add_executable(log_reader_test ${CMAKE_CURRENT_LIST_DIR}/log_reader_test.cc)
target_link_libraries(log_reader_test PRIVATE pidlab_logreader GTest::gtest_main)
gtest_discover_tests(log_reader_test DISCOVERY_TIMEOUT 60)

add_executable(plot_test ${CMAKE_CURRENT_LIST_DIR}/plot_test.cc)
target_link_libraries(plot_test PRIVATE pidlab_plot GTest::gtest_main)
gtest_discover_tests(plot_test DISCOVERY_TIMEOUT 60)
