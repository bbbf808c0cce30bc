# The WebAssembly page (issue 14): scripts/web builds web/ with Debian's emscripten into
# <build>/web/site/; web.browser loads it in headless Chromium (tests/web/). The wasm build is a
# separate emscripten CMake project, so here it is a ctest fixture, not a target of this build.
# A missing emcc, node, npm or chromium fails the tests; they are never skipped.
option(GRADEL_WEB "Build and test the WebAssembly page in ctest (needs emscripten, chromium, node)" ON)
if(GRADEL_WEB AND GRADEL_BUILD_TESTS AND NOT GRADEL_SANITIZE)
  enable_testing()
  set(GRADEL_WEB_DIR ${CMAKE_BINARY_DIR}/web)
  add_test(NAME web.build COMMAND ${CMAKE_COMMAND} -E env GRADEL_WEB_BUILD=${GRADEL_WEB_DIR} GRADEL_WEB_JOBS=2
           ${CMAKE_CURRENT_SOURCE_DIR}/scripts/web)
  add_test(NAME web.browser COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tests/web/run_browser_test ${GRADEL_WEB_DIR}/site
           --screenshot ${GRADEL_WEB_DIR}/web.png)
  set_tests_properties(web.build PROPERTIES FIXTURES_SETUP gradel_web_site TIMEOUT 1800 PROCESSORS 2)
  set_tests_properties(web.browser PROPERTIES FIXTURES_REQUIRED gradel_web_site TIMEOUT 300)
endif()
