# ivoa_lcm_types(TARGET name CPP_ROOT dir [JAR_NAME name] LCM_FILES f1.lcm ...)
#
# Generates C++ headers (C++11 mode, into the build tree) for LCM type files,
# one struct per file, named after the file, each with a `package` line.
# Creates an INTERFACE target whose include root is a SYSTEM directory (the
# generated code is not warning-clean). Each decode() is then patched to
# refuse an array count its bytes cannot hold (GuardLcmArrays.cmake). When
# Java is available, also builds a jar that lcm-spy can load.
set(IVOA_LCM_GUARD_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/GuardLcmArrays.cmake)

function(ivoa_lcm_types)
  cmake_parse_arguments(ARG "" "TARGET;CPP_ROOT;JAR_NAME" "LCM_FILES" ${ARGN})
  set(headers "")
  set(java_files "")
  foreach(lcm_file ${ARG_LCM_FILES})
    get_filename_component(stem ${lcm_file} NAME_WE)
    file(STRINGS ${lcm_file} package_line REGEX "^[ \t]*package[ \t]+[A-Za-z0-9_.]+[ \t]*;")
    if(NOT package_line)
      message(FATAL_ERROR "${lcm_file}: an LCM type file must have a `package` line")
    endif()
    string(REGEX REPLACE "^[ \t]*package[ \t]+([A-Za-z0-9_.]+).*" "\\1" package "${package_line}")
    string(REPLACE "." "/" package_dir "${package}")
    list(APPEND headers ${ARG_CPP_ROOT}/${package_dir}/${stem}.hpp)
    list(APPEND java_files ${CMAKE_CURRENT_BINARY_DIR}/java/${package_dir}/${stem}.java)
  endforeach()

  add_custom_command(
    OUTPUT ${headers}
    COMMAND ${LCM_GEN_EXECUTABLE} --cpp --cpp-std c++11 --cpp-hpath ${ARG_CPP_ROOT} ${ARG_LCM_FILES}
    COMMAND ${CMAKE_COMMAND} "-DHEADERS=${headers}" -P ${IVOA_LCM_GUARD_SCRIPT}
    DEPENDS ${ARG_LCM_FILES} ${IVOA_LCM_GUARD_SCRIPT}
    COMMENT "lcm-gen: C++ headers for ${ARG_TARGET}"
    VERBATIM)
  add_custom_target(${ARG_TARGET}_gen DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_gen)
  target_include_directories(${ARG_TARGET} SYSTEM INTERFACE ${ARG_CPP_ROOT})
  target_link_libraries(${ARG_TARGET} INTERFACE PkgConfig::LCM)

  if(ARG_JAR_NAME)
    find_package(Java COMPONENTS Development)
    find_file(LCM_JAR lcm.jar PATHS /usr/share/java NO_DEFAULT_PATH)
    if(Java_FOUND AND LCM_JAR)
      include(UseJava)
      add_custom_command(
        OUTPUT ${java_files}
        COMMAND ${LCM_GEN_EXECUTABLE} --java --jpath ${CMAKE_CURRENT_BINARY_DIR}/java ${ARG_LCM_FILES}
        DEPENDS ${ARG_LCM_FILES}
        COMMENT "lcm-gen: Java classes for ${ARG_TARGET}"
        VERBATIM)
      add_jar(${ARG_TARGET}_jar
        SOURCES ${java_files}
        INCLUDE_JARS ${LCM_JAR}
        OUTPUT_NAME ${ARG_JAR_NAME}
        OUTPUT_DIR ${CMAKE_BINARY_DIR}/share/java)
    else()
      message(STATUS "Java or lcm.jar not found: the lcm-spy types jar is not built")
    endif()
  endif()
endfunction()
