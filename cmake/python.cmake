# GRADEL_BUILD_PYTHON: the Python package `gradel` for Debian's /usr/bin/python3 with
# python3-numpy: the extension python/gradel_module.cpp (pybind11) as gradel/gradel.*.so next to
# the pure-Python files of python/gradel/ (study.py, stubs), all in <build>/python/gradel/, so
# that PYTHONPATH=<build>/python imports the same package `pip install .` installs (setup.py
# drives this file's target). Its ctest tests: the pytest suite and the example against the build
# tree, and python_pip_install (a fresh venv, pip install ., pytest against the installed
# package). Skipped in the sanitizer build (an ASan-instrumented module needs libasan preloaded
# into the interpreter) and, with a message, when pybind11 or numpy is missing.
set(GRADEL_PYTHON_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter the module is built for")

# The package's pure-Python files (python/gradel/), copied next to the extension.
set(GRADEL_PYTHON_FILES __init__.py study.py gradel.pyi py.typed)

if(NOT GRADEL_SANITIZE AND EXISTS ${GRADEL_PYTHON_EXECUTABLE})
  set(PYBIND11_FINDPYTHON ON)
  set(Python_EXECUTABLE ${GRADEL_PYTHON_EXECUTABLE})
  find_package(Python COMPONENTS Interpreter Development.Module QUIET)
  find_package(pybind11 CONFIG QUIET)
  execute_process(COMMAND ${GRADEL_PYTHON_EXECUTABLE} -c "import numpy" RESULT_VARIABLE _gradel_numpy ERROR_QUIET OUTPUT_QUIET)
  if(NOT pybind11_FOUND OR NOT Python_FOUND OR NOT _gradel_numpy EQUAL 0)
    message(STATUS "gradel: pybind11, Python headers or numpy for ${GRADEL_PYTHON_EXECUTABLE} not found; Python module skipped")
  else()
    set(_pkg ${CMAKE_BINARY_DIR}/python/gradel)
    pybind11_add_module(gradel_python NO_EXTRAS ${CMAKE_CURRENT_SOURCE_DIR}/python/gradel_module.cpp)  # NO_EXTRAS: no LTO (its serial-link warning)
    # The module is PYBIND11_MODULE(gradel, ...): its file is gradel/gradel.<abi>.so, imported as
    # gradel.gradel and re-exported by gradel/__init__.py.
    set_target_properties(gradel_python PROPERTIES OUTPUT_NAME gradel LIBRARY_OUTPUT_DIRECTORY ${_pkg})
    target_link_libraries(gradel_python PRIVATE gradel::core)
    target_compile_options(gradel_python PRIVATE -Wall -Wextra)
    set(_copied)
    foreach(f ${GRADEL_PYTHON_FILES})
      add_custom_command(OUTPUT ${_pkg}/${f}
                         COMMAND ${CMAKE_COMMAND} -E copy_if_different ${CMAKE_CURRENT_SOURCE_DIR}/python/gradel/${f} ${_pkg}/${f}
                         DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/python/gradel/${f})
      list(APPEND _copied ${_pkg}/${f})
    endforeach()
    add_custom_target(gradel_python_files ALL DEPENDS ${_copied})
    add_dependencies(gradel_python gradel_python_files)

    if(GRADEL_BUILD_TESTS)
      set(_env "PYTHONPATH=${CMAKE_BINARY_DIR}/python" "GRADEL_SOURCE_DIR=${CMAKE_CURRENT_SOURCE_DIR}" "PYTHONDONTWRITEBYTECODE=1")
      add_test(NAME python_pytest
               COMMAND ${GRADEL_PYTHON_EXECUTABLE} -m pytest -q -p no:cacheprovider ${CMAKE_CURRENT_SOURCE_DIR}/python/tests
               WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
      add_test(NAME python_example
               COMMAND ${GRADEL_PYTHON_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/examples/python_example.py --duration 0.2
               WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
      set_tests_properties(python_pytest python_example PROPERTIES ENVIRONMENT "${_env}" TIMEOUT 300)
      # pip install . into a fresh venv (Debian's numpy / pytest / distributed seen through
      # --system-site-packages), reusing this build tree's extension, then the same suite
      # against the installed package.
      add_test(NAME python_pip_install
               COMMAND sh ${CMAKE_CURRENT_SOURCE_DIR}/python/tests/pip_install_test.sh
                       ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_BINARY_DIR} ${GRADEL_PYTHON_EXECUTABLE})
      set_tests_properties(python_pip_install PROPERTIES TIMEOUT 600 LABELS python)
    endif()
  endif()
endif()
