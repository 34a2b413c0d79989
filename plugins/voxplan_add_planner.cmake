# voxplan_add_planner(name SOURCES ... [LIBS ...] [OUTPUT_DIRECTORY dir]): a planner plugin
# libvoxplan_planner_<name>.so, the file name `voxplan explore --planner <name>` looks for. It
# sees only the planner API (plus header-only LIBS such as Eigen); hidden visibility leaves
# vp_planner_entry as its one exported symbol.
#
# One definition for the in-tree planners (plugins/CMakeLists.txt includes this file) and for
# out-of-tree ones (installed beside voxplanConfig.cmake, with planner_exports.map). In-tree the
# module gets the project's warning flags and lands in ${VOXPLAN_PLANNER_DIR}; out of tree it
# lands in the calling folder's build folder unless OUTPUT_DIRECTORY says otherwise.
function(voxplan_add_planner name)
  cmake_parse_arguments(ARG "" "OUTPUT_DIRECTORY" "SOURCES;LIBS" ${ARGN})
  if(NOT ARG_OUTPUT_DIRECTORY)
    if(VOXPLAN_PLANNER_DIR)
      set(ARG_OUTPUT_DIRECTORY ${VOXPLAN_PLANNER_DIR})
    else()
      set(ARG_OUTPUT_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    endif()
  endif()
  add_library(voxplan_planner_${name} MODULE ${ARG_SOURCES})
  if(COMMAND voxplan_target_defaults)
    voxplan_target_defaults(voxplan_planner_${name})
  endif()
  target_link_libraries(voxplan_planner_${name} PRIVATE voxplan::planner_api ${ARG_LIBS})
  # planner_cpp.h is C++20 (a C planner needs only planner_api.h).
  if(CMAKE_CXX_COMPILER_LOADED)
    target_compile_features(voxplan_planner_${name} PRIVATE cxx_std_20)
  endif()
  set_target_properties(voxplan_planner_${name} PROPERTIES
    PREFIX "lib" OUTPUT_NAME voxplan_planner_${name}
    LIBRARY_OUTPUT_DIRECTORY ${ARG_OUTPUT_DIRECTORY}
    C_VISIBILITY_PRESET hidden CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  # An undefined symbol fails the build, not the dlopen; the version script exports the entry
  # symbol alone (visibility presets cannot hide std:: template instantiations). Not under clang's
  # sanitizers: there a module takes the runtime's symbols from the executable that loads it.
  set(exports ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/planner_exports.map)
  target_link_options(voxplan_planner_${name} PRIVATE -Wl,--version-script=${exports})
  if(NOT ((VOXPLAN_SANITIZE OR VOXPLAN_FUZZ) AND CMAKE_CXX_COMPILER_ID STREQUAL "Clang"))
    target_link_options(voxplan_planner_${name} PRIVATE -Wl,--no-undefined)
  endif()
  set_target_properties(voxplan_planner_${name} PROPERTIES LINK_DEPENDS ${exports})
endfunction()
