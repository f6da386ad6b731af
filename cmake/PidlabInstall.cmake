# Install helpers. Every library is installed into the export set
# pidlabTargets (static archives, so the libraries they link privately are
# exported too) and appears to users as pidlab::<export name>, the same name
# as its alias in this build; its include/ tree goes to <prefix>/include.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)
set(PIDLAB_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/pidlab)

# pidlab_library(<target> <name> [HEADERS_INSTALLED | NOT_INSTALLED]): a
# folder's library as every folder exports it: its include/ folder public
# (in the build and installed), the alias pidlab::<name>, and its
# installation with that include/ tree (HEADERS_INSTALLED: the folder's other
# library installs the headers; NOT_INSTALLED: used in this build only).
function(pidlab_library target name)
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                             $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  add_library(pidlab::${name} ALIAS ${target})
  if("HEADERS_INSTALLED" IN_LIST ARGN)
    pidlab_install_library(${target} ${name})
  elseif(NOT "NOT_INSTALLED" IN_LIST ARGN)
    pidlab_install_library(${target} ${name} ${CMAKE_CURRENT_SOURCE_DIR}/include)
  endif()
endfunction()

# pidlab_install_library(<target> <export name> [<include dir>])
function(pidlab_install_library target export_name)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  install(TARGETS ${target} EXPORT pidlabTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  if(ARGC GREATER 2)
    install(DIRECTORY ${ARGV2}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
  endif()
endfunction()

# pidlab_install_package(): the CMake package (pidlabConfig.cmake, its
# version file, pidlabTargets.cmake with the pidlab:: namespace) and
# pidlab.pc. Called once, after every folder has installed its targets.
function(pidlab_install_package)
  install(EXPORT pidlabTargets NAMESPACE pidlab:: FILE pidlabTargets.cmake
          DESTINATION ${PIDLAB_INSTALL_CMAKEDIR})
  configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/pidlabConfig.cmake.in
                                ${PROJECT_BINARY_DIR}/pidlabConfig.cmake
                                INSTALL_DESTINATION ${PIDLAB_INSTALL_CMAKEDIR})
  # 0.x: a minor version may break the API.
  write_basic_package_version_file(${PROJECT_BINARY_DIR}/pidlabConfigVersion.cmake
                                   VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
  install(FILES ${PROJECT_BINARY_DIR}/pidlabConfig.cmake ${PROJECT_BINARY_DIR}/pidlabConfigVersion.cmake
          DESTINATION ${PIDLAB_INSTALL_CMAKEDIR})
  # The libraries in link order (each before what it links); lcmtypes is
  # headers only.
  set(PIDLAB_PC_LIBS "-lpidlab_report -lpidlab_figures -lpidlab_replay_json -lpidlab_identify_json -lpidlab_results -lpidlab_plot -lpidlab_launcher -lpidlab_replay")
  string(APPEND PIDLAB_PC_LIBS " -lpidlab_episode_client -lpidlab_log_reader -lpidlab_tune -lpidlab_identify -lpidlab_analysis -lpidlab_evaluation -lpidlab_io -lpidlab_spec")
  string(APPEND PIDLAB_PC_LIBS " -lpidlab_optim")
  string(APPEND PIDLAB_PC_LIBS " -lpidlab_role_main -lpidlab_plant_roles -lpidlab_controller_role")
  string(APPEND PIDLAB_PC_LIBS " -lpidlab_transport -lpidlab_plant_sim -lpidlab_controller")
  file(RELATIVE_PATH PIDLAB_PC_PREFIX /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
  string(REGEX REPLACE "/$" "" PIDLAB_PC_PREFIX "${PIDLAB_PC_PREFIX}")
  configure_file(${PROJECT_SOURCE_DIR}/cmake/pidlab.pc.in ${PROJECT_BINARY_DIR}/pidlab.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pidlab.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endfunction()
