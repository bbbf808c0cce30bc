# GRADEL_BUILD_VALIDATE: gradel-validate, the physical validation report (issue 5),
# docs/validation/. Plots need /usr/bin/python3 with matplotlib (scripts/packages/validate.txt);
# without it the report is written without pictures.
add_executable(gradel-validate ${CMAKE_CURRENT_SOURCE_DIR}/apps/gradel_validate.cpp)
target_link_libraries(gradel-validate PRIVATE gradel::shared CLI11::CLI11)
target_compile_options(gradel-validate PRIVATE -Wall -Wextra)
