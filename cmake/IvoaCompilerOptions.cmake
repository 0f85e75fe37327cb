# Warnings on everywhere; IVOA_WERROR (on in CI) turns them into errors.
option(IVOA_WERROR "Treat compiler warnings as errors" OFF)

# ccache with the checkout as its base directory: paths under it are hashed
# relative to the build folder, so clones at other paths share the cache.
find_program(CCACHE_PROGRAM ccache)
if(CCACHE_PROGRAM)
  set(IVOA_CCACHE ${CMAKE_COMMAND} -E env CCACHE_BASEDIR=${CMAKE_SOURCE_DIR} ${CCACHE_PROGRAM})
  set(CMAKE_C_COMPILER_LAUNCHER ${IVOA_CCACHE})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${IVOA_CCACHE})
endif()

add_library(ivoa_warnings INTERFACE)
target_compile_options(ivoa_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow=local -Wnon-virtual-dtor -Woverloaded-virtual
  $<$<BOOL:${IVOA_WERROR}>:-Werror>)

# ivoa_add_library(name SOURCES ... DEPS ...): a library under libs/ with
# include/ as its public header root, exported as ivoa::name.
function(ivoa_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(ivoa_${name} ${ARG_SOURCES})
  add_library(ivoa::${name} ALIAS ivoa_${name})
  target_include_directories(ivoa_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(ivoa_${name} PUBLIC ${ARG_DEPS} PRIVATE ivoa_warnings ${ARG_PRIVATE_DEPS})
endfunction()

# ivoa_add_executable(name SOURCES ... DEPS ...): an executable in build/bin.
function(ivoa_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ivoa_warnings ${ARG_DEPS})
endfunction()

# Add every immediate subfolder of the current folder that has a CMakeLists.txt,
# so a new module is picked up by creating its folder. IVOA_SKIP_FOLDERS
# (a list of paths relative to the source root, e.g. "libs/foo;tests/foo")
# leaves some out, for building around work in progress.
set(IVOA_SKIP_FOLDERS "" CACHE STRING "Folders (relative to the source root) not to build")
function(ivoa_add_subfolders)
  file(GLOB children RELATIVE ${CMAKE_CURRENT_SOURCE_DIR} CONFIGURE_DEPENDS
       ${CMAKE_CURRENT_SOURCE_DIR}/*/CMakeLists.txt)
  list(SORT children)
  foreach(child ${children})
    get_filename_component(dir ${child} DIRECTORY)
    file(RELATIVE_PATH rel ${CMAKE_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/${dir})
    if(rel IN_LIST IVOA_SKIP_FOLDERS)
      message(STATUS "Skipping ${rel} (IVOA_SKIP_FOLDERS)")
      continue()
    endif()
    add_subdirectory(${dir})
  endforeach()
endfunction()
