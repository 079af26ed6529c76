# Install rules: public headers, the libraries, the texgrad program, the viewer page, the licence,
# and the packages consumers find them with: CMake (find_package(texgrad CONFIG): texgrad::texgrad
# and texgrad::<module>) and pkg-config (texgrad.pc).
include(CMakePackageConfigHelpers)

get_property(TEXGRAD_MODULES GLOBAL PROPERTY TEXGRAD_MODULES)
set(library_targets texgrad)
foreach(module IN LISTS TEXGRAD_MODULES)
  list(APPEND library_targets texgrad_${module})
  install(DIRECTORY include/texgrad/${module} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/texgrad)
endforeach()
install(TARGETS ${library_targets} EXPORT texgradTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(TARGET texgrad_cli)
  install(TARGETS texgrad_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
if(TEXGRAD_BUILD_VIEWER_PAGE)
  install(DIRECTORY "${TEXGRAD_VIEWER_DIST}/" DESTINATION ${TEXGRAD_VIEWER_INSTALL_DIR})
endif()
install(FILES LICENSE NOTICE README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})

# CMake package. A static texgrad leaves its private libraries (TBB, CHOLMOD, libpng, OpenEXR, ...) to
# the consumer's link, so the package config finds them (FindCHOLMOD.cmake travels with it).
set(TEXGRAD_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/texgrad)
if(BUILD_SHARED_LIBS)
  set(TEXGRAD_STATIC OFF)
else()
  set(TEXGRAD_STATIC ON)
endif()
install(EXPORT texgradTargets NAMESPACE texgrad:: DESTINATION ${TEXGRAD_CMAKE_DIR})
configure_package_config_file(cmake/texgradConfig.cmake.in texgradConfig.cmake
                              INSTALL_DESTINATION ${TEXGRAD_CMAKE_DIR})
# 0.x: a new minor version may change the API.
write_basic_package_version_file(texgradConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/texgradConfig.cmake"
              "${PROJECT_BINARY_DIR}/texgradConfigVersion.cmake" cmake/FindCHOLMOD.cmake
        DESTINATION ${TEXGRAD_CMAKE_DIR})

# pkg-config: the library modules, each before the modules it uses (static link order).
get_property(modules GLOBAL PROPERTY TEXGRAD_LIBRARY_MODULES)
list(REVERSE modules)
list(TRANSFORM modules PREPEND "-ltexgrad_")
list(JOIN modules " " TEXGRAD_PC_LIBS)
# The .pc file finds the prefix from its own place, so a relocated prefix still works.
file(RELATIVE_PATH TEXGRAD_PC_PREFIX "/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/")
string(REGEX REPLACE "/$" "" TEXGRAD_PC_PREFIX "${TEXGRAD_PC_PREFIX}")
configure_file(cmake/texgrad.pc.in texgrad.pc @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/texgrad.pc" DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
