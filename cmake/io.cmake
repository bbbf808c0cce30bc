# Volume and mesh readers (src/io/*.cpp, compiled into gradel_core by the top-level glob):
# zlib for gzip-encoded NRRD / .nii.gz, and the NIfTI-1/2 header layouts from libnifti2-dev.
find_package(ZLIB REQUIRED)
find_path(GRADEL_NIFTI_INCLUDE_DIR nifti1.h PATH_SUFFIXES nifti REQUIRED)
target_link_libraries(gradel_core PUBLIC ZLIB::ZLIB)
target_include_directories(gradel_core PRIVATE ${GRADEL_NIFTI_INCLUDE_DIR})
