# GRADEL_BUILD_BENCH: gradel-bench, the speed benchmark (issue 4), printing CSV (bench/run.sh).
add_executable(gradel-bench ${CMAKE_CURRENT_SOURCE_DIR}/bench/gradel_bench.cpp)
target_link_libraries(gradel-bench PRIVATE gradel::shared CLI11::CLI11)
target_compile_options(gradel-bench PRIVATE -Wall -Wextra)
if(GRADEL_BUILD_TESTS)
  enable_testing()
  add_test(NAME bench.real_smoke COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tests/scripts/bench_smoke.sh $<TARGET_FILE:gradel-bench>)
  set_tests_properties(bench.real_smoke PROPERTIES TIMEOUT 300)
  add_test(NAME bench.contact_smoke
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tests/scripts/bench_contact_smoke.sh $<TARGET_FILE:gradel-bench>)
  set_tests_properties(bench.contact_smoke PROPERTIES TIMEOUT 300)
  add_test(NAME bench.drill_smoke
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tests/scripts/bench_drill_smoke.sh $<TARGET_FILE:gradel-bench>)
  set_tests_properties(bench.drill_smoke PROPERTIES TIMEOUT 120)
  add_test(NAME bench.split_smoke
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tests/scripts/bench_split_smoke.sh $<TARGET_FILE:gradel-bench>)
  set_tests_properties(bench.split_smoke PROPERTIES TIMEOUT 120)
endif()

# examples/haptic_loop.cpp: a 1 kHz haptic loop (virtual coupling, contact force fed back) that
# reports its time per iteration (bench/results/*-haptic.csv); the smoke test runs 50 iterations
# on a small ball and checks that the body pushed the proxy (a force was fed back).
add_executable(haptic_loop ${CMAKE_CURRENT_SOURCE_DIR}/examples/haptic_loop.cpp)
target_link_libraries(haptic_loop PRIVATE gradel::core)
target_compile_options(haptic_loop PRIVATE -Wall -Wextra)
if(GRADEL_BUILD_TESTS)
  add_test(NAME bench.haptic_loop_smoke
           COMMAND sh -c "$<TARGET_FILE:haptic_loop> --size 12 --voxel 0.01 --seconds 0.7 | grep -Eq '\"max_force_N\": [0-9.]*[1-9]'")
  set_tests_properties(bench.haptic_loop_smoke PROPERTIES TIMEOUT 120)
endif()
