# A second `simit` built from the same sources without -march=native, for the arithmetic
# contract's test (docs/arithmetic.md): native and generic builds must print the same bits.
#
# The twin targets are copies of the project's own libraries, made from their properties after
# every folder has been added, so a layer's CMakeLists.txt needs no change for them. They set
# the target property SIMIT_GENERIC, which the top-level -march=native generator expression
# reads. simit_frontend is shared, not copied: it does no floating-point arithmetic (it parses
# literals with strtod and prints them), and sharing it saves a quarter of the extra build.
# The JIT's code generator (simit_jit_cpu) is shared too: the code it emits targets the host
# either way, and it links nothing of the project but the frontend.

set(SIMIT_GENERIC_SHARED simit_frontend simit_jit_cpu)

# The twin of a link item: project libraries get a `_generic` copy, anything else is kept.
function(simit_generic_item item out)
  if(TARGET ${item} AND NOT item IN_LIST SIMIT_GENERIC_SHARED)
    get_target_property(imported ${item} IMPORTED)
    get_target_property(type ${item} TYPE)
    if(NOT imported AND type STREQUAL "STATIC_LIBRARY")
      simit_generic_twin(${item})
      set(${out} ${item}_generic PARENT_SCOPE)
      return()
    endif()
  endif()
  set(${out} ${item} PARENT_SCOPE)
endfunction()

# Rewrites a list of link items, including those wrapped as $<LINK_ONLY:item>.
function(simit_generic_links items out)
  set(result)
  foreach(item IN LISTS items)
    if(item MATCHES "^\\$<LINK_ONLY:([^>]+)>$")
      simit_generic_item(${CMAKE_MATCH_1} twin)
      list(APPEND result "$<LINK_ONLY:${twin}>")
    else()
      simit_generic_item(${item} twin)
      list(APPEND result ${twin})
    endif()
  endforeach()
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

# Creates ${target}_generic (a static library or an executable) once.
function(simit_generic_twin target)
  if(TARGET ${target}_generic)
    return()
  endif()
  get_target_property(type ${target} TYPE)
  get_target_property(dir ${target} SOURCE_DIR)
  get_target_property(sources ${target} SOURCES)
  set(absolute)
  foreach(s IN LISTS sources)
    if(NOT IS_ABSOLUTE ${s})
      set(s ${dir}/${s})
    endif()
    list(APPEND absolute ${s})
  endforeach()
  if(type STREQUAL "EXECUTABLE")
    add_executable(${target}_generic ${absolute})
  else()
    add_library(${target}_generic STATIC ${absolute})
  endif()
  foreach(prop INCLUDE_DIRECTORIES COMPILE_DEFINITIONS COMPILE_OPTIONS COMPILE_FEATURES
               LINK_OPTIONS INTERFACE_INCLUDE_DIRECTORIES INTERFACE_COMPILE_DEFINITIONS
               INTERFACE_COMPILE_OPTIONS INTERFACE_SYSTEM_INCLUDE_DIRECTORIES
               INTERFACE_LINK_OPTIONS)
    get_target_property(value ${target} ${prop})
    if(value)
      set_property(TARGET ${target}_generic PROPERTY ${prop} "${value}")
    endif()
  endforeach()
  foreach(prop LINK_LIBRARIES INTERFACE_LINK_LIBRARIES)
    get_target_property(value ${target} ${prop})
    if(value)
      simit_generic_links("${value}" twins)
      set_property(TARGET ${target}_generic PROPERTY ${prop} "${twins}")
    endif()
  endforeach()
  set_target_properties(${target}_generic PROPERTIES SIMIT_GENERIC ON)
  if(type STREQUAL "EXECUTABLE")
    # Beside the native one, under a name of its own.
    get_target_property(out_dir ${target} BINARY_DIR)
    set_target_properties(${target}_generic PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${out_dir}
                          OUTPUT_NAME ${target}-generic)
  endif()
endfunction()
