# Tuner tests (Tune, Ceres cross-check, stability rejection, paper comparison).
add_executable(tune_test ${CMAKE_CURRENT_SOURCE_DIR}/tune_test.cc)
target_link_libraries(tune_test PRIVATE pidlab_tuner GTest::gtest_main)
gtest_discover_tests(tune_test TEST_PREFIX "tune_test." DISCOVERY_TIMEOUT 60)
add_test(NAME cli.tune COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/cli/tune_cli_test.sh $<TARGET_FILE:pidlab>)
add_test(NAME integration.tune_over_trio_equals_local
         COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/integration/tune_lcm_test.sh $<TARGET_FILE:pidlab>)
set_tests_properties(integration.tune_over_trio_equals_local PROPERTIES TIMEOUT 300)
