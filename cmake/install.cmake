# What `cmake --install` puts under the prefix (GNUInstallDirs), in two components that CPack
# turns into two .debs:
#   runtime (voxplan)      bin/voxplan, lib/voxplan/planners/libvoxplan_planner_*.so, the
#                          Python package (lib/python3/dist-packages/voxplan under /usr)
#   dev     (voxplan-dev)  lib/libvoxplan_*.a, include/voxplan/<folder>/*.h, the CMake package
#                          (lib/cmake/voxplan: voxplan::<name> targets, voxplan_add_planner) and
#                          the pkg-config files (lib/pkgconfig/voxplan*.pc)
# Headers keep their in-tree include paths ("core/status.h") below include/voxplan, so code
# written against the package reads like code in this tree. Nothing here changes the build.
include(CMakePackageConfigHelpers)
set(VOXPLAN_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/voxplan)
set(VOXPLAN_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/voxplan)
set(VOXPLAN_INSTALL_PKGCONFIGDIR ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The exported libraries (voxplan_<name> as voxplan::<name>) and the folders of their headers.
# eval links CGAL, which is GPL, and explore sits on eval: those two are an export set of their
# own, the `eval` component, so that find_package(voxplan) alone never drags CGAL into a consumer.
set(exported core fusion io pipeline distributed)
set(header_folders core fusion io pipeline distributed)
set(exported_gpl)
if(NOT VOXPLAN_ENGINE_ONLY)
  list(APPEND exported viewer planning sim planner_api plugin_host)
  list(APPEND header_folders viewer_offscreen planning sim)
  set(exported_gpl eval explore)
  list(APPEND header_folders eval explore)
endif()
# The headers are C++20: consumers compile them as such (the build itself sets the standard).
set_property(TARGET voxplan_core APPEND PROPERTY
  INTERFACE_COMPILE_FEATURES $<INSTALL_INTERFACE:cxx_std_20>)

foreach(folder ${header_folders})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/
    DESTINATION ${VOXPLAN_INSTALL_INCLUDEDIR}/${folder} COMPONENT dev
    FILES_MATCHING PATTERN "*.h")
endforeach()

# install(TARGETS ... EXPORT set) for voxplan_<name> in names, exported as voxplan::<name>.
function(voxplan_install_libraries set)
  set(targets)
  foreach(name ${ARGN})
    set_target_properties(voxplan_${name} PROPERTIES EXPORT_NAME ${name})
    list(APPEND targets voxplan_${name})
  endforeach()
  install(TARGETS ${targets} EXPORT ${set}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
    INCLUDES DESTINATION ${VOXPLAN_INSTALL_INCLUDEDIR})
  install(EXPORT ${set} NAMESPACE voxplan:: DESTINATION ${VOXPLAN_INSTALL_CMAKEDIR} COMPONENT dev)
endfunction()
voxplan_install_libraries(voxplanTargets ${exported})
if(exported_gpl)
  voxplan_install_libraries(voxplanEvalTargets ${exported_gpl})
endif()

if(NOT VOXPLAN_ENGINE_ONLY)
  # The planner SDK: the two headers a plugin may include, voxplan_add_planner and its linker
  # script; and the planners `voxplan explore` ships with (the test planners stay in the build).
  install(FILES ${PROJECT_SOURCE_DIR}/plugins/planner_api.h ${PROJECT_SOURCE_DIR}/plugins/planner_cpp.h
    DESTINATION ${VOXPLAN_INSTALL_INCLUDEDIR}/plugins COMPONENT dev)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/plugins/host/
    DESTINATION ${VOXPLAN_INSTALL_INCLUDEDIR}/plugins/host COMPONENT dev
    FILES_MATCHING PATTERN "*.h")
  install(FILES ${PROJECT_SOURCE_DIR}/plugins/voxplan_add_planner.cmake
    ${PROJECT_SOURCE_DIR}/plugins/planner_exports.map
    DESTINATION ${VOXPLAN_INSTALL_CMAKEDIR} COMPONENT dev)
  install(TARGETS voxplan_planner_omt voxplan_planner_greedy voxplan_planner_voronoi
    voxplan_planner_taskflow voxplan_planner_tensorfield
    LIBRARY DESTINATION ${VOXPLAN_INSTALL_PLANNERDIR} COMPONENT runtime)
endif()
if(TARGET voxplan)
  install(TARGETS voxplan RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
endif()

# The Python package (python/CMakeLists.txt calls these): where Debian's /usr/bin/python3 finds it
# for the prefix. Under /usr that is lib/python3/dist-packages (Debian's own packages' folder);
# under any other prefix lib/python3.<minor>/dist-packages, which for /usr/local is on that
# interpreter's sys.path; for another prefix, PYTHONPATH=<prefix>/lib/python3.<minor>/dist-packages.
# -DVOXPLAN_INSTALL_PYTHONDIR=<dir relative to the prefix> overrides it. In the runtime .deb.
set(VOXPLAN_INSTALL_PYTHONDIR "" CACHE STRING
  "Where the Python package goes, relative to the prefix (empty: chosen for Debian's python3)")
function(voxplan_python_install_dir out major minor)
  if(VOXPLAN_INSTALL_PYTHONDIR)
    set(dir ${VOXPLAN_INSTALL_PYTHONDIR})
  elseif(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
    set(dir lib/python${major}/dist-packages)
  else()
    set(dir lib/python${major}.${minor}/dist-packages)
  endif()
  set(${out} ${dir} PARENT_SCOPE)
endfunction()
# The extension module `target` and `files` (from `source_dir`) into <dir>/voxplan.
function(voxplan_install_python target dir source_dir)
  install(TARGETS ${target} LIBRARY DESTINATION ${dir}/voxplan COMPONENT runtime)
  foreach(f ${ARGN})
    install(FILES ${source_dir}/${f} DESTINATION ${dir}/voxplan COMPONENT runtime)
  endforeach()
endfunction()

# The CMake package: find_dependency for every package the exported targets link (the
# libraries are static, so their private dependencies too).
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/voxplanConfig.cmake.in
  ${PROJECT_BINARY_DIR}/voxplanConfig.cmake INSTALL_DESTINATION ${VOXPLAN_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/voxplanConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/voxplanConfig.cmake
  ${PROJECT_BINARY_DIR}/voxplanConfigVersion.cmake
  DESTINATION ${VOXPLAN_INSTALL_CMAKEDIR} COMPONENT dev)

# pkg-config: voxplan-<name>.pc per library (Requires: the voxplan libraries and system packages
# it links, so that plain `pkg-config --libs` links the static archives), and voxplan.pc for
# all but the GPL pair. Relative to the .pc file's folder, so any --prefix works.
file(RELATIVE_PATH VOXPLAN_PC_PREFIX ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig ${CMAKE_INSTALL_PREFIX})
string(REGEX REPLACE "/$" "" VOXPLAN_PC_PREFIX "${VOXPLAN_PC_PREFIX}")
function(voxplan_pkg_config name description)
  cmake_parse_arguments(ARG "" "" "REQUIRES;LIBS" ${ARGN})
  set(VOXPLAN_PC_NAME ${name})
  set(VOXPLAN_PC_DESCRIPTION ${description})
  list(JOIN ARG_REQUIRES " " VOXPLAN_PC_REQUIRES)
  list(JOIN ARG_LIBS " " VOXPLAN_PC_LIBS)
  configure_file(${CMAKE_CURRENT_FUNCTION_LIST_DIR}/voxplan.pc.in
    ${PROJECT_BINARY_DIR}/pkgconfig/${name}.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/${name}.pc
    DESTINATION ${VOXPLAN_INSTALL_PKGCONFIGDIR} COMPONENT dev)
endfunction()
set(pc_libdir "-L\${libdir}")
voxplan_pkg_config(voxplan-core "voxel blocks, hash map, TSDF volume, queries, ray casting"
  REQUIRES eigen3 tbb LIBS ${pc_libdir} -lvoxplan_core)
voxplan_pkg_config(voxplan-fusion "TSDF integration, tracking, marching cubes"
  REQUIRES voxplan-core LIBS ${pc_libdir} -lvoxplan_fusion -lopencv_imgproc -lopencv_core)
voxplan_pkg_config(voxplan-io "dataset readers, trajectories, images, mesh and map files"
  REQUIRES voxplan-core libpng libjpeg zlib libdeflate assimp libtiff-4 OpenEXR
  LIBS ${pc_libdir} -lvoxplan_io
  -lrosbag_storage -lrostime -lroscpp_serialization -lcpp_common -lconsole_bridge -lroslz4 -lbz2)
voxplan_pkg_config(voxplan-pipeline "whole fusion jobs over a dataset"
  REQUIRES voxplan-fusion voxplan-io LIBS ${pc_libdir} -lvoxplan_pipeline)
set(pc_mpi "")
if(VOXPLAN_HAVE_MPI)
  set(pc_mpi ompi-c)  # Debian's OpenMPI
endif()
voxplan_pkg_config(voxplan-distributed "sharded fusion over MPI ranks, sharded maps, the task farm"
  REQUIRES voxplan-pipeline nlohmann_json ${pc_mpi} LIBS ${pc_libdir} -lvoxplan_distributed)
set(umbrella voxplan-pipeline voxplan-distributed)
if(NOT VOXPLAN_ENGINE_ONLY)
  voxplan_pkg_config(voxplan-viewer "CPU shading of ray casts and meshes, orbits, top-down maps"
    REQUIRES voxplan-core LIBS ${pc_libdir} -lvoxplan_viewer)
  voxplan_pkg_config(voxplan-planning "planning and floor maps, geodesics, OctoMap export"
    REQUIRES voxplan-fusion voxplan-io octomap LIBS ${pc_libdir} -lvoxplan_planning)
  voxplan_pkg_config(voxplan-sim "simulated worlds, Embree rendering, robots, tours"
    REQUIRES voxplan-io voxplan-viewer LIBS ${pc_libdir} -lvoxplan_sim -lembree3)
  voxplan_pkg_config(voxplan-planner-api "the planner plugin C ABI and its C++ layer")
  voxplan_pkg_config(voxplan-plugin-host "loads and supervises planner plugins"
    REQUIRES voxplan-core voxplan-planner-api LIBS ${pc_libdir} -lvoxplan_plugin_host -ldl -pthread)
  voxplan_pkg_config(voxplan-eval "scoring against ground truth (links CGAL: GPL)"
    REQUIRES voxplan-sim voxplan-io gmp mpfr LIBS ${pc_libdir} -lvoxplan_eval)
  voxplan_pkg_config(voxplan-explore "the closed exploration loop (on voxplan-eval: GPL)"
    REQUIRES voxplan-planning voxplan-sim voxplan-eval voxplan-plugin-host voxplan-viewer
    LIBS ${pc_libdir} -lvoxplan_explore)
  list(APPEND umbrella voxplan-planning voxplan-sim voxplan-plugin-host)
endif()
voxplan_pkg_config(voxplan "every voxplan library but eval and explore" REQUIRES ${umbrella})

# CPack: `cpack -G DEB` in the build folder writes voxplan_<version>_<arch>.deb (the CLI and the
# planners; dpkg-shlibdeps finds their Debian dependencies) and voxplan-dev_... (the rest; it
# needs the -dev packages of what the static libraries link).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME voxplan)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "CPU voxel-hashing TSDF reconstruction engine and multi-robot exploration planners")
set(CPACK_PACKAGE_CONTACT "voxplan developers <voxplan@users.noreply.example>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME voxplan)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME voxplan-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(dev_depends libeigen3-dev libtbb-dev libpng-dev libjpeg62-turbo-dev libdeflate-dev
  libassimp-dev nlohmann-json3-dev libopencv-imgproc-dev libtiff-dev libopenexr-dev libimath-dev
  librosbag-storage-dev)
if(VOXPLAN_HAVE_MPI)
  list(APPEND dev_depends libopenmpi-dev)
endif()
if(NOT VOXPLAN_ENGINE_ONLY)
  list(APPEND dev_depends liboctomap-dev libembree-dev)
  # Only the eval component needs CGAL.
  set(CPACK_DEBIAN_DEV_PACKAGE_SUGGESTS libcgal-dev)
endif()
list(JOIN dev_depends ", " CPACK_DEBIAN_DEV_PACKAGE_DEPENDS)
include(CPack)
cpack_add_component(runtime DISPLAY_NAME "voxplan CLI and planners")
cpack_add_component(dev DISPLAY_NAME "voxplan libraries, headers and planner SDK" DEPENDS runtime)
