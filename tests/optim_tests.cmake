# Unit tests of the generic optimisers (pidlab_optim), one executable.
add_executable(optim_test
  ${CMAKE_CURRENT_LIST_DIR}/nelder_mead_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/paper_nelder_mead_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/genetic_algorithm_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/pso_gsa_test.cc)
target_link_libraries(optim_test pidlab_optim GTest::gtest_main)
include(GoogleTest)
gtest_discover_tests(optim_test)
