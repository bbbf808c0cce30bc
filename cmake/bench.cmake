# GRADEL_BUILD_BENCH: gradel-bench, the speed benchmark (issue 4), printing CSV (bench/run.sh).
add_executable(gradel-bench ${CMAKE_CURRENT_SOURCE_DIR}/bench/gradel_bench.cpp)
target_link_libraries(gradel-bench PRIVATE gradel::shared CLI11::CLI11)
target_compile_options(gradel-bench PRIVATE -Wall -Wextra)
if(GRADEL_BUILD_TESTS)
  enable_testing()
  add_test(NAME bench.real_smoke COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tests/scripts/bench_smoke.sh $<TARGET_FILE:gradel-bench>)
  set_tests_properties(bench.real_smoke PROPERTIES TIMEOUT 300)
endif()
