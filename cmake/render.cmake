# GRADEL_BUILD_RENDER: gradel_render (OpenGL 3.3 drawing, EGL offscreen context, PNG files
# through stb), the `gradel render` subcommand and the headless picture test. OpenGL, EGL and stb
# stay out of gradel_core.
find_package(PkgConfig REQUIRED)
pkg_check_modules(STB REQUIRED IMPORTED_TARGET stb)
set(OpenGL_GL_PREFERENCE GLVND)
find_package(OpenGL REQUIRED COMPONENTS OpenGL EGL)

list(TRANSFORM GRADEL_RENDER_SOURCES PREPEND ${CMAKE_CURRENT_SOURCE_DIR}/)
add_library(gradel_render STATIC ${GRADEL_RENDER_SOURCES})
target_link_libraries(gradel_render PUBLIC gradel::shared OpenGL::OpenGL OpenGL::EGL
                                    PRIVATE PkgConfig::STB nlohmann_json::nlohmann_json)
target_compile_options(gradel_render PRIVATE -Wall -Wextra)

# The CLI gets the `render` subcommand (its CLI11 options live in apps/render_cli.cpp).
if(GRADEL_BUILD_CLI)
  list(TRANSFORM GRADEL_CLI_RENDER_SOURCES PREPEND ${CMAKE_CURRENT_SOURCE_DIR}/)
  target_sources(gradel PRIVATE ${GRADEL_CLI_RENDER_SOURCES})
  target_link_libraries(gradel PRIVATE gradel_render)
  target_compile_definitions(gradel PRIVATE GRADEL_WITH_RENDER=1)
endif()

# ---- tests: real pictures, headless (EGL surfaceless); the viewer's window test is added by
# cmake/viewer.cmake -----------------------------------------------------------------------------
if(GRADEL_BUILD_TESTS)
  find_package(GTest REQUIRED)
  add_executable(gradel_render_tests ${CMAKE_CURRENT_SOURCE_DIR}/tests/render/test_render.cpp)
  target_link_libraries(gradel_render_tests PRIVATE gradel_render GTest::gtest_main PkgConfig::STB)
  target_compile_options(gradel_render_tests PRIVATE -Wall -Wextra)
  target_compile_definitions(gradel_render_tests PRIVATE
    GRADEL_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}"
    GRADEL_CLI_PATH="$<TARGET_FILE:gradel>")
  # The viewer's path: cmake/viewer.cmake sets it when the viewer is built ($<TARGET_FILE> of a
  # target that does not exist fails generation even inside a false $<IF>).
  if(NOT GRADEL_BUILD_VIEWER)
    target_compile_definitions(gradel_render_tests PRIVATE GRADEL_VIEW_PATH="gradel-view-not-built")
  endif()
  add_dependencies(gradel_render_tests gradel)
  # One ctest test: a missing GL fails it (never skipped).
  add_test(NAME render.headless COMMAND gradel_render_tests --gtest_filter=-ViewerWindow.*)
  # Under GRADEL_SANITIZE, Mesa's driver leaks a few once-per-process allocations and is
  # unloaded before the leak check, so they cannot be told apart by module: leak checking is off
  # for the render tests only (address and undefined-behaviour checks stay on; gradel's own code
  # is leak-checked by gradel_tests).
  set_tests_properties(render.headless PROPERTIES TIMEOUT 300 ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
endif()
