# The Python module `gradel` (python/gradel_module.cpp, pybind11) for Debian's /usr/bin/python3
# with python3-numpy, built into <build>/python/, and its pytest suite + example as ctest tests.
# Skipped in the sanitizer build (an ASan-instrumented module needs libasan preloaded into the
# interpreter) and, with a message, when pybind11 or numpy is missing.
option(GRADEL_PYTHON "Build the Python module" ON)
set(GRADEL_PYTHON_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter the module is built for")

if(GRADEL_PYTHON AND NOT GRADEL_SANITIZE AND EXISTS ${GRADEL_PYTHON_EXECUTABLE})
  set(PYBIND11_FINDPYTHON ON)
  set(Python_EXECUTABLE ${GRADEL_PYTHON_EXECUTABLE})
  find_package(Python COMPONENTS Interpreter Development.Module QUIET)
  find_package(pybind11 CONFIG QUIET)
  execute_process(COMMAND ${GRADEL_PYTHON_EXECUTABLE} -c "import numpy" RESULT_VARIABLE _gradel_numpy ERROR_QUIET OUTPUT_QUIET)
  if(NOT pybind11_FOUND OR NOT Python_FOUND OR NOT _gradel_numpy EQUAL 0)
    message(STATUS "gradel: pybind11, Python headers or numpy for ${GRADEL_PYTHON_EXECUTABLE} not found; Python module skipped")
  else()
    # The module is a shared object that links the static core library into it.
    set_target_properties(gradel_core PROPERTIES POSITION_INDEPENDENT_CODE ON)
    pybind11_add_module(gradel_python NO_EXTRAS ${CMAKE_CURRENT_SOURCE_DIR}/python/gradel_module.cpp)  # NO_EXTRAS: no LTO (its serial-link warning)
    set_target_properties(gradel_python PROPERTIES OUTPUT_NAME gradel LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/python)
    target_link_libraries(gradel_python PRIVATE gradel::core)
    target_compile_options(gradel_python PRIVATE -Wall -Wextra)
    if(GRADEL_BUILD_TESTS)
      enable_testing()
      set(_env "PYTHONPATH=${CMAKE_BINARY_DIR}/python" "GRADEL_SOURCE_DIR=${CMAKE_CURRENT_SOURCE_DIR}" "PYTHONDONTWRITEBYTECODE=1")
      add_test(NAME python_pytest
               COMMAND ${GRADEL_PYTHON_EXECUTABLE} -m pytest -q -p no:cacheprovider ${CMAKE_CURRENT_SOURCE_DIR}/python/tests
               WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
      add_test(NAME python_example
               COMMAND ${GRADEL_PYTHON_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/python/example.py --duration 0.2
               WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
      set_tests_properties(python_pytest python_example PROPERTIES ENVIRONMENT "${_env}" TIMEOUT 300)
    endif()
  endif()
endif()
