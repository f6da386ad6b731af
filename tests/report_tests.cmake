# Ziegler-Nichols tuning and the paper report (issue 6).
add_executable(ziegler_nichols_test ${CMAKE_CURRENT_LIST_DIR}/ziegler_nichols_test.cc)
target_link_libraries(ziegler_nichols_test PRIVATE pidlab_tuner GTest::gtest_main)
gtest_discover_tests(ziegler_nichols_test DISCOVERY_TIMEOUT 60)
