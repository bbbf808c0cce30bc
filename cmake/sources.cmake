# Which source file builds which target: the one list per target, shared by the top-level
# CMakeLists.txt and the standalone fuzz build (fuzz/CMakeLists.txt). Paths are relative to the
# repository root. A new source file joins exactly one of these lists.

# gradel_core: the engine. Needs Eigen (and zlib + the NIfTI header layouts for the
# readers below); no windowing, no OpenGL, no command-line parser.
set(GRADEL_CORE_SOURCES
  src/bodies.cpp
  src/carve.cpp                     # carving: the event (re-layout, state carried over) and a tool's voxels
  src/carve_cells.cpp               # carving's lattice kernels: mass cells, trilinear transfer, voxel owners
  src/carve_blade.cpp               # a blade's kerf: the voxels near the rectangle it swept
  src/pieces.cpp                    # a carved body's connected pieces, each a body of its own
  src/carve_scene.cpp               # carving in a built scene: the body replaced in its World
  src/body_contacts.cpp             # body contacts: the stage, resolve()'s loop of rounds over the phases below
  src/body_contact_bounds.cpp       # broad phase per step and round: motion bounds, which candidates to look up
  src/body_contact_tracks.cpp       # broad phase kept across steps: per pair of bodies, candidates and faces
  src/body_contact_grid.cpp         # the faces' grid the phases query (body_contact_grid.h)
  src/body_contact_narrow_phase.cpp # nearest triangle, pseudo-normal sign test (pseudo_normal.h), self-contact
  src/body_contact_response.cpp     # projections, friction, restitution: impulses that add no energy
  src/body_contact_warm_start.cpp   # the last stage's contacts as round 0's
  src/body_contact_takeback.cpp     # last resort: unreachable findings dropped, bodies taken back
  src/body_contact_energy.cpp       # the stage never adds energy: its excess out of the touched vertices' motion
  src/body_contact_proximity.cpp    # the frame-size integrators' broad phase and proximity list
  src/contact_surface.cpp           # a body's closed contact surface (contact_surface.h)
  src/triangle_queries.cpp          # closest point on a triangle, winding number
  src/contacts.cpp
  src/contact_work.cpp
  src/divergence.cpp
  src/element.cpp
  src/element_strain.cpp
  src/coarse_space.cpp
  src/element_stiffness.cpp
  src/element_stage.cpp
  src/display_normals.cpp
  src/embedding.cpp
  src/external_force.cpp
  src/huge_pages.cpp
  src/isosurface.cpp
  src/layout.cpp
  src/material.cpp
  src/mesh.cpp
  src/model.cpp
  src/output.cpp
  src/overlaps.cpp
  src/pins.cpp
  src/plane.cpp                  # a 2D scene put into its plane z = 0 once (normalizeFor2D)
  src/factor_solve.cpp
  src/projective.cpp
  src/large_step.cpp
  src/rotation_fit.cpp
  src/settings_check.cpp
  src/shapes.cpp
  src/size_limits.cpp
  src/slow_stage.cpp
  src/stability.cpp
  src/stability_warm.cpp
  src/surface.cpp
  src/team_chunks.cpp
  src/thread_team.cpp
  src/volume.cpp
  src/world.cpp                  # World: creation, the step's list of stages (step_context.h), pins
  src/world_metrics.cpp          # World's figures (energies, momenta, stress) per body and combined
  src/integrator_choice.cpp      # integrator / period-rule names, "auto"'s cost model
  src/start_overlap_release.cpp  # start overlaps released step by step
  src/step_explicit.cpp          # stage: explicit advance (element frames, the fused vertex pass), the team
  src/step_implicit.cpp          # stage: implicit advance (two solves, held contacts, pair constraints)
  src/step_large.cpp             # stage: large-step advance (midpoint substeps away from contacts)
  src/step_obstacles.cpp         # stage: manipulator and wall contacts, the sweep, the force ledger
  src/step_body_contacts.cpp     # stage: body contacts after the advance, the walls' re-pass
  src/world_replace.cpp          # World::replaceModel: the world over a carved body's new model
  # Scene files (JSON, nlohmann_json as a private build dependency) and the scene builder.
  src/scene_build.cpp
  src/scene_io.cpp               # scene files: the top level (which section when), loadScene
  src/scene_json.cpp             # the strict JSON reader: duplicate keys, Fields, one-line messages
  src/scene_schema_bodies.cpp    # the schema: bodies, shapes, sources, materials
  src/scene_schema_world.cpp)    # the schema: simulation, domain, body contact, pins, manipulators

# gradel_shared: the layer between the engine and its tools, used by `gradel` (run, render),
# gradel-view, gradel-validate, gradel-bench and the tests; not part of the installed package.
set(GRADEL_SHARED_SOURCES
  src/shared/frame_loop.cpp      # the frame loop of `gradel run` and `gradel render`
  src/shared/run_budget.cpp      # how long a run will take, refused beyond a budget
  src/shared/rate_window.cpp     # the viewer's rates over the last second
  src/shared/realtime_size.cpp   # which body sizes run in real time, estimated before building
  src/shared/scene_presets.cpp   # scenes built in code (the benchmark's)
  src/shared/step_batch.cpp      # one batch of a real-time front end's steps (viewer, web page)
  src/shared/step_pacer.cpp      # how many steps the viewer's stepping thread takes next
  src/shared/validation.cpp)     # the cantilever / stretch experiments behind gradel-validate and the tests

# The volume and mesh readers (docs/io.md), part of gradel_core: zlib for gzip-encoded NRRD and
# .nii.gz, the NIfTI-1/2 header layouts from libnifti2-dev (headers only). Also fuzzed (fuzz/).
set(GRADEL_IO_SOURCES
  src/io/binvox.cpp
  src/io/byte_stream.cpp
  src/io/grey_levels.cpp
  src/io/mesh_file.cpp
  src/io/nifti.cpp
  src/io/nrrd.cpp
  src/io/raw_volume.cpp
  src/io/read_limits.cpp
  src/io/volume_file.cpp
  src/io/vox.cpp
  src/io/voxelize.cpp)

# gradel_render (GRADEL_BUILD_RENDER): OpenGL 3.3 drawing, EGL offscreen context, PNG files (stb).
set(GRADEL_RENDER_SOURCES
  src/image.cpp
  src/render/body_table.cpp
  src/render/camera.cpp
  src/render/display_budget.cpp
  src/render/draw_list.cpp
  src/render/layout_picture.cpp
  src/render/manipulator_drag.cpp
  src/render/offscreen.cpp
  src/render/render_command.cpp
  src/render/renderer.cpp)

# The `gradel` command-line program; apps/render_cli.cpp adds `gradel render` (GRADEL_BUILD_RENDER).
set(GRADEL_CLI_SOURCES apps/gradel_main.cpp)
set(GRADEL_CLI_RENDER_SOURCES apps/render_cli.cpp)

# gradel_tests (GRADEL_BUILD_TESTS): GoogleTest + rapidcheck, one file per engine part.
set(GRADEL_TEST_SOURCES
  tests/test_bodies.cpp
  tests/test_carve.cpp
  tests/test_pieces.cpp
  tests/test_blade.cpp
  tests/test_carve_labels.cpp
  tests/test_external_force.cpp
  tests/test_body_contacts.cpp
  tests/test_body_contacts_large.cpp
  tests/test_frame_holds.cpp
  tests/test_broad_phase.cpp
  tests/test_cantilever.cpp
  tests/test_cli.cpp
  tests/test_contact_energy.cpp
  tests/test_contacts.cpp
  tests/test_contact_forces.cpp
  tests/test_divergence.cpp
  tests/test_contact_supply.cpp
  tests/test_start_overlap.cpp
  tests/test_dynamics.cpp
  tests/test_element.cpp
  tests/test_element_strain.cpp
  tests/test_element_stiffness.cpp
  tests/test_element_stage.cpp
  tests/test_embedding.cpp
  tests/test_factor_solve.cpp
  tests/test_team_chunks.cpp
  tests/test_thread_governor.cpp
  tests/test_frame_loop.cpp
  tests/test_golden.cpp
  tests/test_impacts.cpp
  tests/test_implicit.cpp
  tests/test_integration.cpp
  tests/test_coarse_space.cpp
  tests/test_large_step.cpp
  tests/test_io_embedded.cpp
  tests/test_io_grey_readers.cpp
  tests/test_io_meshes.cpp
  tests/test_io_samples.cpp
  tests/test_io_voxel_readers.cpp
  tests/test_layout.cpp
  tests/test_material.cpp
  tests/test_model.cpp
  tests/test_output.cpp
  tests/test_pins.cpp
  tests/test_plane.cpp
  tests/test_region_damping.cpp
  tests/test_regions.cpp
  tests/test_rotation_fit.cpp
  tests/test_scene_io.cpp
  tests/test_scenes.cpp
  tests/test_settings_check.cpp
  tests/test_shapes.cpp
  tests/test_stability.cpp
  tests/test_stability_warm.cpp
  tests/test_poisson.cpp
  tests/test_step_pacer.cpp
  tests/test_surface.cpp)
