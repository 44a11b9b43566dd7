# `cmake --install <build> --prefix P`: the library, its public headers under P/include/crumple,
# the CMake package (find_package(crumple) -> crumple::crumple) and crumple.pc. The command
# installs itself (app/CMakeLists.txt).
include(CMakePackageConfigHelpers)

install(TARGETS crumple_lib EXPORT crumpleTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# crumple.h includes these two by paths relative to itself.
install(FILES api/crumple/crumple.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/crumple)
install(FILES model/params.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/crumple/model)
install(FILES sim/manipulators.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/crumple/sim)

set(_crumple_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/crumple)
install(EXPORT crumpleTargets NAMESPACE crumple:: DESTINATION ${_crumple_cmake_dir})
configure_package_config_file(api/crumpleConfig.cmake.in ${CMAKE_CURRENT_BINARY_DIR}/crumpleConfig.cmake
                              INSTALL_DESTINATION ${_crumple_cmake_dir})
# 0.x: a minor version may break the API, so only the same MAJOR.MINOR is compatible.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/crumpleConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/crumpleConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/crumpleConfigVersion.cmake
        DESTINATION ${_crumple_cmake_dir})

# pkg-config: a static library lists what it needs in Requires.private / Libs.private.
# Relocatable: the prefix is found from the .pc file's own folder, so `cmake --install --prefix P`
# works for any P (pkg-config's ${pcfiledir}).
set(CRUMPLE_PC_REQUIRES_PRIVATE "tbb tinyobjloader_double")
file(RELATIVE_PATH CRUMPLE_PC_UP /x/${CMAKE_INSTALL_LIBDIR}/pkgconfig /x)
string(REGEX REPLACE "/$" "" CRUMPLE_PC_UP "${CRUMPLE_PC_UP}")
configure_file(api/crumple.pc.in ${CMAKE_CURRENT_BINARY_DIR}/crumple.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/crumple.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
