# GRADEL_BUILD_VIEWER: gradel-view (GLFW + Dear ImGui over gradel_render) and its windowed test.
find_package(PkgConfig REQUIRED)
pkg_check_modules(IMGUI REQUIRED IMPORTED_TARGET imgui)
pkg_check_modules(GLFW REQUIRED IMPORTED_TARGET glfw3)

add_executable(gradel-view ${CMAKE_CURRENT_SOURCE_DIR}/apps/gradel_view.cpp)
target_link_libraries(gradel-view PRIVATE gradel_render PkgConfig::IMGUI PkgConfig::GLFW CLI11::CLI11
                                          nlohmann_json::nlohmann_json)
target_compile_options(gradel-view PRIVATE -Wall -Wextra)
target_compile_definitions(gradel-view PRIVATE GRADEL_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")

# gradel-view under a virtual X server (the test binary is cmake/render.cmake's); xvfb-run
# missing = failure, not a skip.
if(GRADEL_BUILD_TESTS)
  add_dependencies(gradel_render_tests gradel-view)
  target_compile_definitions(gradel_render_tests PRIVATE GRADEL_VIEW_PATH="$<TARGET_FILE:gradel-view>")
  find_program(XVFB_RUN xvfb-run)
  if(NOT XVFB_RUN)
    set(XVFB_RUN xvfb-run)
  endif()
  add_test(NAME render.viewer_xvfb COMMAND ${XVFB_RUN} -a -s "-screen 0 1024x768x24"
           $<TARGET_FILE:gradel_render_tests> --gtest_filter=ViewerWindow.*)
  set_tests_properties(render.viewer_xvfb PROPERTIES TIMEOUT 300 ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
endif()
