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

# pidlab_lcm_frozen_versions(FILE <type.lcm> OUT_VAR <var> [LAYOUT_HEADER <path>])
#
# A type that only ever gains fields at its end marks each place it once
# ended with a line "//@frozen <name>" (<name>: the frozen copy's type name).
# For each marker this writes <build>/lcm_frozen/<name>.lcm at configure
# time: the package line and the fields above the marker, as struct <name>.
# Such a copy has the old type's fingerprint (lcm-gen's hash covers the
# fields' names and types, not the type's name), so logs written before an
# append still decode. <var> receives the generated files' paths.
#
# With LAYOUT_HEADER, it also writes a C++ header describing the type's wire
# layout field by field (kFixed with its bytes, kString, kArray of doubles
# counted by the int32 before it), how many fields each version has, and an
# X-macro listing the frozen types, so that the layout check and the log
# reader's table follow the .lcm file instead of restating it.
function(pidlab_lcm_frozen_versions)
  cmake_parse_arguments(ARG "" "FILE;OUT_VAR;LAYOUT_HEADER;FIELDS_HEADER" "" ${ARGN})
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
  set(layout "")     # the C++ initialisers of the fields, in order
  set(xfields "")    # the fields as X-macro entries D, I, S, A, N (FIELDS_HEADER)
  set(count 0)       # fields so far (an int32 count and its array are one)
  set(counts "")     # fields per frozen version
  set(frozen "")     # X(name) per frozen version
  set(pending_count "")  # an int32 field not yet known to count an array
  set(includes "")
  foreach(line IN LISTS lines)
    if(line MATCHES "^package ([A-Za-z0-9_]+)")
      set(package ${CMAKE_MATCH_1})
      string(REPLACE "@SEMI@" ";" head "${line}")
    elseif(line MATCHES "^struct ${stem}")
      set(in_struct ON)
    elseif(in_struct AND line MATCHES "^[ \t]*//@frozen ([A-Za-z0-9_]+)")
      set(name ${CMAKE_MATCH_1})
      set(text "${head}\n\n// Generated from lcmtypes/${ARG_FILE} (the fields above its line\n// \"//@frozen ${name}\") by pidlab_lcm_frozen_versions: do not edit.\nstruct ${name}\n{${body}}\n")
      # Written only when it changes, so that a reconfigure rebuilds nothing.
      file(CONFIGURE OUTPUT ${out_dir}/${name}.lcm CONTENT "${text}" @ONLY)
      list(APPEND outputs ${out_dir}/${name}.lcm)
      if(pending_count)
        math(EXPR count "${count} + 1")
        string(APPEND layout "    {\"${pending_count}\", WireField::kFixed, 4},\n")
        string(APPEND xfields " \\\n  N(${pending_count})")
        set(pending_count "")
      endif()
      string(APPEND counts "${count}, ")
      string(APPEND frozen " X(${name})")
      string(APPEND includes "#include <${package}/${name}.hpp>\n")
    elseif(in_struct AND line MATCHES "^[ \t]*[a-z]")
      string(REGEX REPLACE "[ \t]*//.*$" "" field "${line}")
      string(REPLACE "@SEMI@" ";" field "${field}")
      string(APPEND body "\n${field}")
      if(NOT field MATCHES "^[ \t]*([a-z0-9_]+)[ \t]+([a-z0-9_]+)(\\[([a-z0-9_]+)\\])?[ \t]*;")
        message(FATAL_ERROR "${ARG_FILE}: cannot read the field '${field}'")
      endif()
      set(type ${CMAKE_MATCH_1})
      set(fname ${CMAKE_MATCH_2})
      set(dim "${CMAKE_MATCH_4}")
      if(pending_count AND NOT (dim STREQUAL pending_count))
        math(EXPR count "${count} + 1")
        string(APPEND layout "    {\"${pending_count}\", WireField::kFixed, 4},\n")
        string(APPEND xfields " \\\n  N(${pending_count})")
        set(pending_count "")
      endif()
      if(NOT dim STREQUAL "")
        if(NOT (type STREQUAL "double" AND dim STREQUAL pending_count))
          message(FATAL_ERROR "${ARG_FILE}: ${fname}: only double arrays counted by the int32 before them")
        endif()
        math(EXPR count "${count} + 1")
        string(APPEND layout "    {\"${fname}\", WireField::kArray, 8},\n")
        string(APPEND xfields " \\\n  A(${fname}, ${pending_count})")
        set(pending_count "")
      elseif(type STREQUAL "int32_t")
        set(pending_count ${fname})
      elseif(type STREQUAL "string")
        math(EXPR count "${count} + 1")
        string(APPEND layout "    {\"${fname}\", WireField::kString, 0},\n")
        string(APPEND xfields " \\\n  S(${fname})")
      elseif(type MATCHES "^(double|int64_t)$")
        math(EXPR count "${count} + 1")
        string(APPEND layout "    {\"${fname}\", WireField::kFixed, 8},\n")
        if(type STREQUAL "double")
          string(APPEND xfields " \\\n  D(${fname})")
        else()
          string(APPEND xfields " \\\n  I(${fname})")
        endif()
      else()
        message(FATAL_ERROR "${ARG_FILE}: ${fname}: type ${type} has no layout here")
      endif()
    endif()
  endforeach()
  if(pending_count)
    math(EXPR count "${count} + 1")
    string(APPEND layout "    {\"${pending_count}\", WireField::kFixed, 4},\n")
        string(APPEND xfields " \\\n  N(${pending_count})")
  endif()
  if(ARG_LAYOUT_HEADER)
    set(text "#pragma once\n// Generated from lcmtypes/${ARG_FILE} by pidlab_lcm_frozen_versions: do not edit.\n// The wire layout of ${stem}, field by field, and its versions.\n\n${includes}#include <${package}/${stem}.hpp>\n\nnamespace pidlab::lcm_layout::${stem} {\n\nenum class WireField { kFixed, kString, kArray };\nstruct Field {\n  const char* name@SEMI@\n  WireField kind@SEMI@\n  int bytes@SEMI@  // kFixed: the field's, kArray: an element's\n}@SEMI@\n\ninline constexpr Field kFields[] = {\n${layout}}@SEMI@\n\n// Fields of each frozen version, in order, then of the current type.\ninline constexpr int kFieldsInVersion[] = {${counts}${count}}@SEMI@\ninline constexpr int kVersions = sizeof kFieldsInVersion / sizeof kFieldsInVersion[0]@SEMI@\n\n}  // namespace pidlab::lcm_layout::${stem}\n\n// X(type) for every frozen copy, oldest first.\n#define PIDLAB_${stem}_FROZEN(X)${frozen}\n")
    string(REPLACE "@SEMI@" ";" text "${text}")
    file(CONFIGURE OUTPUT ${ARG_LAYOUT_HEADER} CONTENT "${text}" @ONLY)
  endif()
  if(ARG_FIELDS_HEADER)
    string(TOUPPER ${stem} upper)
    set(text "/* Generated from lcmtypes/${ARG_FILE} by pidlab_lcm_frozen_versions: do not edit. */\n/* Every field of ${stem} in wire order, as an X-macro for C and C++: D(name) a\n * double, I(name) an int64_t, S(name) a string, A(name, count) an array of\n * doubles counted by the int32_t count, N(name) an int32_t counting nothing.\n * The generated C and C++ types name their members as the .lcm file does, so\n * one expansion reads every field of either (the controllers' --print-configs,\n * pidlab replay's \"config\"). */\n#ifndef PIDLAB_${upper}_FIELDS_H\n#define PIDLAB_${upper}_FIELDS_H\n\n#define PIDLAB_${upper}_FIELDS(D, I, S, A, N)${xfields}\n\n#endif\n")
    file(CONFIGURE OUTPUT ${ARG_FIELDS_HEADER} CONTENT "${text}" @ONLY)
  endif()
  set(${ARG_OUT_VAR} ${outputs} PARENT_SCOPE)
endfunction()
