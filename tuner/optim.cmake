# Generic, plant-independent optimisers: Nelder-Mead (standard and the paper's
# three-point variant), a real-coded genetic algorithm and PSOGSA.
# See docs/optimisers.md.
add_library(pidlab_optim
  ${CMAKE_CURRENT_LIST_DIR}/src/optim/optimizer.cc
  ${CMAKE_CURRENT_LIST_DIR}/src/optim/nelder_mead.cc
  ${CMAKE_CURRENT_LIST_DIR}/src/optim/paper_nelder_mead.cc
  ${CMAKE_CURRENT_LIST_DIR}/src/optim/genetic_algorithm.cc
  ${CMAKE_CURRENT_LIST_DIR}/src/optim/pso_gsa.cc)
target_include_directories(pidlab_optim PUBLIC ${CMAKE_CURRENT_LIST_DIR}/include)
target_link_libraries(pidlab_optim PUBLIC Eigen3::Eigen)
