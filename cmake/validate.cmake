# GRADEL_BUILD_VALIDATE: gradel-validate, the physical validation report (issue 5),
# docs/validation/. Plots need /usr/bin/python3 with matplotlib (scripts/packages/validate.txt);
# without it the report is written without pictures.
add_executable(gradel-validate ${CMAKE_CURRENT_SOURCE_DIR}/apps/gradel_validate.cpp)
target_link_libraries(gradel-validate PRIVATE gradel::shared CLI11::CLI11)
target_compile_options(gradel-validate PRIVATE -Wall -Wextra)
# Its plotting scripts are files of the source tree, next to the committed CSV files they read:
# a build tree runs them in place, an installed gradel-validate from DATADIR/gradel/validation
# (install.cmake), found relative to the binary.
set(_gradel_scripts ${CMAKE_CURRENT_SOURCE_DIR}/docs/validation)
set(GRADEL_VALIDATE_SCRIPTS ${_gradel_scripts}/plots.py ${_gradel_scripts}/large_step_plot.py
    ${_gradel_scripts}/poisson_plot.py)
file(RELATIVE_PATH _gradel_scripts_from_bin ${CMAKE_INSTALL_FULL_BINDIR}
     ${CMAKE_INSTALL_FULL_DATADIR}/gradel/validation)
target_compile_definitions(gradel-validate PRIVATE
  GRADEL_VALIDATION_SCRIPTS_SOURCE="${_gradel_scripts}"
  GRADEL_VALIDATION_SCRIPTS_FROM_BIN="${_gradel_scripts_from_bin}")
