# GRADEL_INSTALL: `cmake --install` puts gradel's headers, libgradel_core and the CMake package
# (lib/cmake/gradel/gradelConfig.cmake + version file) into the prefix, so that a consumer
# writes find_package(gradel) and links gradel::core (examples/consumer/). Component
# `gradel_dev` is the library part; `gradel_apps` the programs.
include(CMakePackageConfigHelpers)
set(GRADEL_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/gradel)

install(TARGETS gradel_core EXPORT gradelTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT gradel_dev
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT gradel_dev
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT gradel_dev)
# The engine's headers; render/ and shared/ belong to gradel_render and gradel_shared (the tools'
# layers), which are not installed.
install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/gradel DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        COMPONENT gradel_dev FILES_MATCHING PATTERN "*.h" PATTERN "render" EXCLUDE PATTERN "shared" EXCLUDE)
install(EXPORT gradelTargets NAMESPACE gradel:: DESTINATION ${GRADEL_CMAKE_DIR} COMPONENT gradel_dev)
configure_package_config_file(${CMAKE_CURRENT_SOURCE_DIR}/cmake/gradelConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/gradelConfig.cmake INSTALL_DESTINATION ${GRADEL_CMAKE_DIR})
# 0.x: a minor version may break the API, so only the same minor version is compatible.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/gradelConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/gradelConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/gradelConfigVersion.cmake
        DESTINATION ${GRADEL_CMAKE_DIR} COMPONENT gradel_dev)

foreach(app gradel gradel-view gradel-bench gradel-validate)
  if(TARGET ${app})
    install(TARGETS ${app} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT gradel_apps)
  endif()
endforeach()
if(TARGET gradel-validate)  # its plotting scripts (validate.cmake)
  install(FILES ${GRADEL_VALIDATE_SCRIPTS} DESTINATION ${CMAKE_INSTALL_DATADIR}/gradel/validation COMPONENT gradel_apps)
endif()

# ctest install_consumer: installs the library component from this build tree into a scratch
# prefix (a copy), then configures, builds and runs examples/consumer against it.
if(GRADEL_BUILD_TESTS)
  add_test(NAME install_consumer
           COMMAND ${CMAKE_COMMAND}
             -DBUILD_DIR=${CMAKE_BINARY_DIR}
             -DSOURCE_DIR=${CMAKE_CURRENT_SOURCE_DIR}
             -DWORK_DIR=${CMAKE_BINARY_DIR}/install-test
             -DGENERATOR=${CMAKE_GENERATOR}
             -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
             -DCXX_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER}
             -P ${CMAKE_CURRENT_SOURCE_DIR}/cmake/test_install_consumer.cmake)
  set_tests_properties(install_consumer PROPERTIES TIMEOUT 600 LABELS install)
endif()
