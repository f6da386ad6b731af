# pidlab_lcm_cpp(TARGET <name> PACKAGE <pkg> FILES a.lcm b.lcm ...)
#
# Generates C++ headers with lcm-gen at build time and exposes them through an
# INTERFACE library. Debian's LCM 1.3.1 ships no CMake helpers, so this is ours.
# --cpp-std=c++11 is needed for constants; the headers are added as SYSTEM
# includes because generated code does not pass our warning flags.
function(pidlab_lcm_cpp)
  cmake_parse_arguments(ARG "" "TARGET;PACKAGE" "FILES" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/lcmgen_cpp)
  set(headers)
  foreach(f ${ARG_FILES})
    get_filename_component(stem ${f} NAME_WE)
    list(APPEND headers ${out_dir}/${ARG_PACKAGE}/${stem}.hpp)
  endforeach()
  set(abs_files)
  foreach(f ${ARG_FILES})
    list(APPEND abs_files ${CMAKE_CURRENT_SOURCE_DIR}/${f})
  endforeach()
  add_custom_command(
    OUTPUT ${headers}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
    COMMAND ${LCM_GEN_EXECUTABLE} --cpp --cpp-std=c++11 --cpp-hpath ${out_dir} ${abs_files}
    DEPENDS ${abs_files}
    COMMENT "lcm-gen --cpp ${ARG_PACKAGE}"
    VERBATIM)
  add_custom_target(${ARG_TARGET}_gen DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_gen)
  target_include_directories(${ARG_TARGET} SYSTEM INTERFACE $<BUILD_INTERFACE:${out_dir}>
                             $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${ARG_TARGET} INTERFACE PkgConfig::LCM)
endfunction()

# pidlab_lcm_python(TARGET <name> OUT_DIR <dir> FILES a.lcm b.lcm ...)
#
# Generates the Python classes with lcm-gen --python at build time (part of
# `all`): <dir>/<package>/lcmt_*.py and lcm-gen's __init__.py, with
# cmake/python_package_init.py appended (the package's C++ module). They need only
# Python's struct module, not the LCM Python binding (Debian 12 has none).
function(pidlab_lcm_python)
  cmake_parse_arguments(ARG "" "TARGET;PACKAGE;OUT_DIR" "FILES" ${ARGN})
  set(outputs ${ARG_OUT_DIR}/${ARG_PACKAGE}/__init__.py)
  set(abs_files)
  foreach(f ${ARG_FILES})
    get_filename_component(stem ${f} NAME_WE)
    list(APPEND outputs ${ARG_OUT_DIR}/${ARG_PACKAGE}/${stem}.py)
    list(APPEND abs_files ${CMAKE_CURRENT_SOURCE_DIR}/${f})
  endforeach()
  add_custom_command(
    OUTPUT ${outputs}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${ARG_OUT_DIR}
    COMMAND ${LCM_GEN_EXECUTABLE} --python --ppath ${ARG_OUT_DIR} ${abs_files}
    COMMAND ${CMAKE_COMMAND} -DTARGET_FILE=${ARG_OUT_DIR}/${ARG_PACKAGE}/__init__.py
            -DTAIL_FILE=${PROJECT_SOURCE_DIR}/cmake/python_package_init.py -P ${PROJECT_SOURCE_DIR}/cmake/AppendFile.cmake
    DEPENDS ${abs_files} ${PROJECT_SOURCE_DIR}/cmake/python_package_init.py
    COMMENT "lcm-gen --python ${ARG_PACKAGE}"
    VERBATIM)
  add_custom_target(${ARG_TARGET} ALL DEPENDS ${outputs})
endfunction()
