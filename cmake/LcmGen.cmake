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
    get_filename_component(abs ${f} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
    list(APPEND abs_files ${abs})
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
    get_filename_component(abs ${f} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
    list(APPEND abs_files ${abs})
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

# pidlab_lcm_frozen_versions(FILE <type.lcm> OUT_VAR <var>)
#
# A type that only ever gains fields at its end marks each place it once
# ended with a line "//@frozen <name>" (<name>: the frozen copy's type name).
# For each marker this writes <build>/lcm_frozen/<name>.lcm at configure
# time: the package line and the fields above the marker, as struct <name>.
# Such a copy has the old type's fingerprint (lcm-gen's hash covers the
# fields' names and types, not the type's name), so logs written before an
# append still decode. <var> receives the generated files' paths.
function(pidlab_lcm_frozen_versions)
  cmake_parse_arguments(ARG "" "FILE;OUT_VAR" "" ${ARGN})
  set(src ${CMAKE_CURRENT_SOURCE_DIR}/${ARG_FILE})
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${src})
  get_filename_component(stem ${ARG_FILE} NAME_WE)
  # Lines as a list: the ';' that ends every field is kept as @SEMI@.
  file(READ ${src} content)
  string(REPLACE ";" "@SEMI@" content "${content}")
  string(REPLACE "\n" ";" lines "${content}")
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/lcm_frozen)
  set(head "")       # the package line
  set(body "")       # the fields so far
  set(in_struct OFF)
  set(outputs)
  foreach(line IN LISTS lines)
    if(line MATCHES "^package ")
      string(REPLACE "@SEMI@" ";" head "${line}")
    elseif(line MATCHES "^struct ${stem}")
      set(in_struct ON)
    elseif(in_struct AND line MATCHES "^[ \t]*//@frozen ([A-Za-z0-9_]+)")
      set(name ${CMAKE_MATCH_1})
      set(text "${head}\n\n// Generated from lcmtypes/${ARG_FILE} (the fields above its line\n// \"//@frozen ${name}\") by pidlab_lcm_frozen_versions: do not edit.\nstruct ${name}\n{${body}}\n")
      # Written only when it changes, so that a reconfigure rebuilds nothing.
      file(CONFIGURE OUTPUT ${out_dir}/${name}.lcm CONTENT "${text}" @ONLY)
      list(APPEND outputs ${out_dir}/${name}.lcm)
    elseif(in_struct AND line MATCHES "^[ \t]*[a-z]")
      string(REGEX REPLACE "[ \t]*//.*$" "" field "${line}")
      string(REPLACE "@SEMI@" ";" field "${field}")
      string(APPEND body "\n${field}")
    endif()
  endforeach()
  set(${ARG_OUT_VAR} ${outputs} PARENT_SCOPE)
endfunction()
