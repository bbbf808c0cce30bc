# GRADEL_BUILD_FUZZ: libFuzzer targets for every reader (fuzz/) and for scene files (fuzz_scene),
# built with clang whatever compiler builds the rest, and bounded fuzz runs registered as ctest tests
# (fuzz_<format>, GRADEL_FUZZ_SECONDS each, from the committed seed corpus fuzz/corpus/<format>/).
# Skipped, with a message, when clang or its
# libFuzzer runtime (Debian: clang, libclang-rt-14-dev) is missing, and in the sanitizer build
# (the fuzz targets carry their own ASan + UBSan).
set(GRADEL_FUZZ_SECONDS 20 CACHE STRING "Seconds each fuzz_<format> ctest test fuzzes")
set(GRADEL_FUZZ_FORMATS binvox vox nrrd nifti raw obj stl ply scene)

if(NOT GRADEL_SANITIZE)
  find_program(GRADEL_CLANGXX NAMES clang++ clang++-14)
  set(GRADEL_LIBFUZZER_FOUND FALSE)
  if(GRADEL_CLANGXX)
    execute_process(COMMAND ${GRADEL_CLANGXX} -print-file-name=libclang_rt.fuzzer-x86_64.a
                    OUTPUT_VARIABLE _fuzzer_lib OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    if(_fuzzer_lib AND EXISTS "${_fuzzer_lib}")
      set(GRADEL_LIBFUZZER_FOUND TRUE)
    else()
      # clang prints the bare name when it has no such file; look in its resource directory.
      execute_process(COMMAND ${GRADEL_CLANGXX} -print-resource-dir OUTPUT_VARIABLE _res OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
      file(GLOB _fuzzer_libs "${_res}/lib/linux/libclang_rt.fuzzer-*.a")
      if(_fuzzer_libs)
        set(GRADEL_LIBFUZZER_FOUND TRUE)
      endif()
    endif()
  endif()

  if(NOT GRADEL_LIBFUZZER_FOUND)
    message(STATUS "gradel: clang++ with libFuzzer not found; fuzz targets skipped")
  else()
    include(ExternalProject)
    set(GRADEL_FUZZ_BIN ${CMAKE_BINARY_DIR}/fuzz)
    ExternalProject_Add(gradel_fuzz
      SOURCE_DIR ${CMAKE_CURRENT_SOURCE_DIR}/fuzz
      BINARY_DIR ${GRADEL_FUZZ_BIN}
      CMAKE_ARGS -DCMAKE_CXX_COMPILER=${GRADEL_CLANGXX} -DCMAKE_BUILD_TYPE=RelWithDebInfo
      INSTALL_COMMAND ""
      BUILD_ALWAYS ON  # the readers' sources live outside the sub-build; let ninja decide
      BUILD_BYPRODUCTS ${GRADEL_FUZZ_BIN}/fuzz_binvox)
    if(GRADEL_BUILD_TESTS)
      foreach(format ${GRADEL_FUZZ_FORMATS})
        # A fresh work corpus first (new inputs are written there), the committed seeds second
        # (read only). Crash reproducers land in the build folder.
        set(_work ${GRADEL_FUZZ_BIN}/work-${format})
        add_test(NAME fuzz_${format}
          COMMAND sh -c "rm -rf '${_work}' && mkdir -p '${_work}' && exec '${GRADEL_FUZZ_BIN}/fuzz_${format}' \
-max_total_time=${GRADEL_FUZZ_SECONDS} -rss_limit_mb=2048 -timeout=10 -max_len=65536 -print_final_stats=1 \
-artifact_prefix='${GRADEL_FUZZ_BIN}/crash-${format}-' '${_work}' '${CMAKE_CURRENT_SOURCE_DIR}/fuzz/corpus/${format}'")
        set_tests_properties(fuzz_${format} PROPERTIES TIMEOUT 300 LABELS fuzz)
      endforeach()
    endif()
  endif()
endif()
