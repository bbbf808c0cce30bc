"""pytest suite of the Python module (run by ctest as python_pytest; see cmake/python.cmake)."""
import os

import numpy as np
import pytest

import gradel

ROOT = os.environ.get("GRADEL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def sample(name):
    return os.path.join(ROOT, "samples", name)


def test_load_volume_is_a_read_only_view_in_x_fastest_order():
    v = gradel.load_volume(sample("ct.nrrd"), threshold=300)
    assert v.dtype == np.bool_ and v.shape == (40, 40, 40)
    assert v.flags["F_CONTIGUOUS"] and not v.flags["OWNDATA"] and not v.flags["WRITEABLE"]
    limb = gradel.load_volume(sample("ct.nrrd"), threshold=-300)
    assert limb.sum() > 3 * v.sum() > 0
    nii = gradel.load_volume(sample("ct.nii.gz"), threshold=300)
    raw = gradel.load_volume(sample("ct.raw"), dims=(40, 40, 40), type="uint8")
    assert (nii == v).all() and (raw == v).all()


@pytest.mark.parametrize("name,options", [
    ("torus.binvox", {}), ("mushroom.vox", {}), ("torus.obj", {"resolution": 24}),
    ("torus.stl", {"resolution": 24}), ("pawn.ply", {"resolution": 20}),
])
def test_every_sample_format_loads(name, options):
    v = gradel.load_volume(sample(name), **options)
    assert v.ndim == 3 and v.sum() > 100


def test_bad_input_raises_input_error_naming_the_file():
    with pytest.raises(gradel.InputError, match="nope.nrrd: cannot read"):
        gradel.load_volume(sample("nope.nrrd"))
    with pytest.raises(ValueError, match="a raw file needs dims and type"):
        gradel.load_volume(sample("ct.raw"))
    with pytest.raises(ValueError, match="empty"):
        gradel.Body.from_array(np.zeros((4, 4, 4), bool))
    with pytest.raises(ValueError, match="the volume is empty: no voxel passes the threshold 5000"):
        gradel.Body.from_file(sample("ct.nrrd"), threshold=5000)


def test_body_from_array_keeps_index_order():
    a = np.zeros((6, 5, 4), bool)
    a[1:3, 2:5, 0:2] = True
    b = gradel.Body.from_array(a, voxel_size=0.02)
    assert b.filled == a.sum() and b.voxel_size == 0.02
    assert (b.voxels == a).all()
    c = gradel.Body.from_array(np.asfortranarray(a.astype(np.float32)))  # any dtype, any order
    assert (c.voxels == a).all()


def test_simulation_views_share_memory_and_step():
    body = gradel.Body.from_shape("sphere", 8)
    sim = gradel.Simulation(body, gravity=[0, 0, 0], dt=1e-4)
    p = sim.positions
    assert p.shape == (sim.num_vertices, 3) and p.dtype == np.float64 and not p.flags["OWNDATA"]
    rest = sim.rest_positions.copy()
    sim.velocities[:] = [0.1, 0.0, 0.0]  # writable view: sets the world's velocities
    sim.step(100)
    assert sim.time == pytest.approx(0.01)
    assert np.allclose(p - rest, [0.001, 0, 0], atol=1e-9)  # the same view saw the motion
    assert sim.masses.sum() == pytest.approx(1000 * body.filled * 0.01 ** 3)
    assert sim.stress.shape == (sim.num_vertices,) and np.allclose(sim.stress, 0, atol=1e-6)  # [Pa]: moved, not strained
    assert sim.strain.shape == (sim.num_vertices,) and np.allclose(sim.strain, 0, atol=1e-9)


def test_stress_is_von_mises_in_pascal():
    body = gradel.Body.from_shape("box", 6)
    sim = gradel.Simulation(body, gravity=[0, 0, 0], youngs_modulus=2e5)
    rest = sim.rest_positions
    stretched = rest.copy()
    stretched[:, 0] = rest[:, 0].mean() + 1.01 * (rest[:, 0] - rest[:, 0].mean())  # 1 % uniaxial, no lateral strain
    sim.positions = stretched
    assert np.allclose(sim.element_stress, 0.01 * 2e5, rtol=1e-6)  # nu = 0: sigma = E eps, von Mises = sigma
    assert np.allclose(sim.stress, 0.01 * 2e5, rtol=1e-6)
    assert sim.metrics()["max_stress"] == pytest.approx(0.01 * 2e5, rel=1e-6)
    assert 0 < sim.metrics()["max_strain"] < 0.05 and sim.element_strain.max() == pytest.approx(sim.metrics()["max_strain"])


def test_poisson_ratio_bulges_a_pressed_box_and_refuses_one_half():
    body = gradel.Body.from_shape("box", 6)
    rest = gradel.Simulation(body).rest_positions
    lo, hi = rest.min(axis=0), rest.max(axis=0)
    length, cx, strain = hi[0] - lo[0], 0.5 * (lo[0] + hi[0]), 0.02
    ratios = {}
    for nu in (0.0, 0.45):
        # pressed 2 % along x between frictionless walls, free in y and z, settled with damping
        sim = gradel.Simulation(body, gravity=[0, 0, 0], damping=60, poisson_ratio=nu, restitution=0, friction=0,
                                domain_min=[cx - 0.5 * length * (1 - strain), -1, -1],
                                domain_max=[cx + 0.5 * length * (1 - strain), 1, 1])
        pressed = rest.copy()
        pressed[:, 0] = cx + (rest[:, 0] - cx) * (1 - strain)
        sim.positions = pressed
        sim.step(4000)
        ext = sim.positions.max(axis=0) - sim.positions.min(axis=0)
        axial, lateral = ext[0] / length - 1, 0.5 * (ext[1] + ext[2]) / length - 1
        ratios[nu] = -lateral / axial
    assert abs(ratios[0.0]) < 0.02  # the paper's element: no bulge
    assert ratios[0.45] == pytest.approx(0.45, rel=0.1)  # lateral / axial strain = nu
    with pytest.raises(ValueError, match="poisson_ratio"):
        gradel.Simulation(body, poisson_ratio=0.5)


def test_manipulator_pushes_the_body():
    body = gradel.Body.from_shape("box", 6)
    sim = gradel.Simulation(body, gravity=[0, 0, 0], damping=0.0, youngs_modulus=1e5)
    i = sim.add_manipulator("sphere", radius=0.02, position=[-0.05, 0.03, 0.03])
    x0 = sim.positions[:, 0].mean()
    p0 = sim.masses @ sim.velocities
    impulse = np.zeros(3)
    t = 0.0
    while t < 0.15:
        t0, t = sim.time, t + 0.005
        sim.move_manipulator(i, [-0.05 + 0.5 * t, 0.03, 0.03], [0.5, 0, 0])
        sim.advance_to(t)
        force, torque = sim.manipulator_force(i)  # averaged over this advance_to's steps
        impulse += np.array(force) * (sim.time - t0)
    assert sim.positions[:, 0].mean() > x0 + 0.005
    # Newton's third law: what the tool received is minus what the body gained.
    dp = sim.masses @ sim.velocities - p0
    assert dp[0] > 1e-3 and np.allclose(impulse, -dp, rtol=0, atol=1e-9 * np.linalg.norm(dp))
    assert len(sim.manipulator_force(i, average=False)[1]) == 3 and sim.wall_force()[0] == [0.0, 0.0, 0.0]
    assert sim.metrics()["max_penetration"] < 1e-3
    assert np.allclose(sim.manipulator_positions[0], [-0.05 + 0.5 * t, 0.03, 0.03])
    with pytest.raises(IndexError):
        sim.move_manipulator(5, [0, 0, 0])


def test_wall_force_per_wall(tmp_path):
    # A box resting on the floor (ymin) of a domain: the floor carries its weight, no other wall anything.
    scene = tmp_path / "rest.json"
    scene.write_text("""{
      "body": {"shape": "box", "size": 4, "layout": "voxel", "position": [0, 0, 0]},
      "simulation": {"gravity": [0, -9.81, 0], "damping": 20},
      "domain": {"min": [-0.5, 0, -0.5], "max": [0.5, 1, 0.5], "restitution": 0}
    }""")
    sim = gradel.Simulation.from_scene(str(scene))
    sim.advance_to(0.4)
    sim.advance_to(0.45)
    weight = sim.masses.sum() * 9.81
    floor, _ = sim.wall_force("ymin")
    assert floor[1] == pytest.approx(-weight, rel=0.02)
    assert sim.wall_force("all")[0] == floor  # the only wall touched: the total, bit for bit
    for w in ("xmin", "xmax", "ymax", "zmin", "zmax"):
        assert sim.wall_force(w)[0] == [0.0, 0.0, 0.0]
    with pytest.raises(ValueError):
        sim.wall_force("floor")


def test_layouts_materials_integrators_and_scene_files():
    body = gradel.Body.from_file(sample("mushroom.vox"), voxel_size=0.01)
    counts = {k: gradel.Simulation(body, layout=k).num_elements for k in ("gradational", "uniform", "voxel")}
    assert counts["gradational"] < counts["uniform"] < counts["voxel"] == body.filled
    fe = gradel.Simulation(body, integrator="forward_euler", scaling="paper", k=5000, damping=2.0)
    fe.step(10)
    with pytest.raises(ValueError, match="layout"):
        gradel.Simulation(body, layout="octree")
    sim = gradel.Simulation.from_scene(os.path.join(ROOT, "scenes", "ct-nrrd.json"))
    sim.advance_to(0.02)
    assert sim.num_vertices > 100 and sim.voxels.sum() > 1000


def test_2d_body_and_surface_arrays():
    sim = gradel.Simulation(gradel.Body.from_array(np.ones((8, 6), bool)), gravity=[0, -9.81])
    sim.step(5)
    assert np.all(sim.positions[:, 2] == 0)
    body = gradel.Simulation(gradel.Body.from_shape("sphere", 8))
    for kind in ("voxel", "smooth"):
        v, t, n = body.surface(kind)
        assert v.shape[1] == 3 and t.shape[1] == 3 and t.dtype == np.uint32 and n.shape == v.shape
        assert t.max() < len(v) and len(t) > 50


def read_obj(path):
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "v":
                vertices.append([float(x) for x in w[1:4]])
            elif w and w[0] == "f":
                faces.append([int(x.split("/")[0]) for x in w[1:]])
    return np.array(vertices), faces


def test_embedded_surface_is_the_mesh_file_carried_by_the_body():
    file_v, file_f = read_obj(sample("torus.obj"))
    sim = gradel.Simulation.from_scene(os.path.join(ROOT, "scenes", "torus-obj.json"))
    v0, t0, n0 = sim.surface("embedded")
    assert v0.shape == file_v.shape and len(t0) == sum(len(f) - 2 for f in file_f)
    # A uniformly scaled, shifted copy of the file's vertices (voxel_size 0.01, resolution 24).
    scale = 0.24 / np.ptp(file_v, axis=0).max()
    np.testing.assert_allclose(v0 - v0[0], scale * (file_v - file_v[0]), atol=1e-12)
    # It moves with the body: a rigid shift of every vertex shifts it exactly.
    sim.positions[:] += [0.1, 0.2, 0.3]
    v1, _, _ = sim.surface("embedded")
    np.testing.assert_allclose(v1, v0 + [0.1, 0.2, 0.3], atol=1e-12)
    # A volume body embeds its isosurface instead; a 2D body has none.
    iso, _, _ = gradel.Simulation(gradel.Body.from_shape("sphere", 8)).surface("embedded")
    assert len(iso) > 50
    with pytest.raises(gradel.InputError):
        gradel.Simulation(gradel.Body.from_array(np.ones((8, 6), bool))).surface("embedded")


def test_several_bodies_ranges_views_metrics_and_surfaces(tmp_path):
    scene = tmp_path / "two.json"
    scene.write_text("""{
      "bodies": [
        {"name": "ball", "shape": "sphere", "size": 6, "position": [-0.1, 0, 0], "velocity": [1, 0, 0]},
        {"shape": "box", "size": 3, "voxel_size": 0.02, "layout": "voxel", "position": [0.1, 0, 0],
         "material": {"density": 500}}
      ],
      "simulation": {"gravity": [0, 0, 0], "damping": 0}
    }""")
    sim = gradel.Simulation.from_scene(str(scene))
    assert sim.num_bodies == 2 and sim.body_names == ["ball", "body1"]
    (a0, a1), (b0, b1) = sim.body_vertex_ranges
    assert a0 == 0 and a1 == b0 and b1 == sim.num_vertices and b1 - b0 == 4 ** 3
    box = sim.body_positions(1)
    assert box.shape == (64, 3) and np.shares_memory(box, sim.positions)
    np.testing.assert_array_equal(box, sim.positions[b0:b1])
    assert (sim.body_velocities(0)[:, 0] == 1).all() and (sim.body_velocities(1) == 0).all()
    sim.step(10)
    each = sim.body_metrics()
    assert each[0]["linear_momentum"][0] > 0.1 and abs(each[1]["linear_momentum"][0]) < 1e-12
    assert sim.metrics()["kinetic_energy"] == each[0]["kinetic_energy"] + each[1]["kinetic_energy"]
    # The box's voxel surface: its 6 faces of 3 x 3 squares, at the box's own positions.
    verts, tris, _ = sim.surface("voxel", body=1)
    assert len(tris) == 6 * 9 * 2 and verts[:, 0].min() >= 0.1 - 1e-9
    with pytest.raises(IndexError):
        sim.body_positions(2)


def test_carve_sphere_and_remove_voxels_take_exactly_the_voxels_mass():
    body = gradel.Body.from_shape("box", 8)
    sim = gradel.Simulation(body, gravity=[0, 0, 0], dt=1e-4)
    sim.velocities[:] = [0.1, 0.0, 0.0]
    mass = sim.masses.sum()
    removed = sim.carve_sphere([0.0, 0.0, 0.0], 0.025)  # a corner of the box, voxels of 1 cm
    assert removed > 0
    assert sim.masses.sum() == pytest.approx(mass - removed * 1000 * 0.01 ** 3, rel=1e-12)
    assert np.allclose(sim.velocities, [0.1, 0.0, 0.0])  # a uniform motion is carried over exactly
    mask = np.zeros((8, 8, 8), dtype=bool)
    mask[7, 7, 7] = True
    assert sim.remove_voxels(0, mask) == 1
    assert sim.masses.sum() == pytest.approx(mass - (removed + 1) * 1000 * 0.01 ** 3, rel=1e-12)
    m = sim.metrics()  # carving's ledger since t = 0
    assert m["removed_voxels"] == removed + 1
    assert m["removed_volume"] == pytest.approx((removed + 1) * 0.01 ** 3, rel=1e-12)
    assert m["removed_mass"] == pytest.approx(mass - sim.masses.sum(), rel=1e-9)
    assert m["removed_momentum"] == pytest.approx([0.1 * m["removed_mass"], 0, 0], rel=1e-9, abs=1e-15)
    sim.step(10)
    assert np.isfinite(sim.positions).all()
    with pytest.raises(ValueError):
        sim.remove_voxels(0, np.zeros((3, 3, 3), dtype=bool))


def test_carve_sphere_with_labels_takes_only_those_regions():
    # The phantom (soft tissue label 1, a stiff inclusion label 2 of 1200 kg/m^3, voxels of 5 mm):
    # a sphere around the inclusion's top takes both regions' voxels without labels, only the
    # tissue's with labels=[1] (each at 1000 kg/m^3).
    scene = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "phantom.json")
    voxel = 1000 * 0.005 ** 3
    both = gradel.Simulation.from_scene(scene)
    mass = both.masses.sum()
    n_both = both.carve_sphere([0.0, 0.05, 0.0], 0.012)
    heavy = (mass - both.masses.sum() - n_both * voxel) / (0.2 * voxel)  # voxels at 1200 kg/m^3
    assert round(heavy) > 0
    soft = gradel.Simulation.from_scene(scene)
    n_soft = soft.carve_sphere([0.0, 0.05, 0.0], 0.012, labels=[1])
    assert n_soft == n_both - round(heavy)
    assert soft.masses.sum() == pytest.approx(mass - n_soft * voxel, rel=1e-12)
    for bad in ([], [0], [1, 1], [70000]):
        with pytest.raises(ValueError):
            soft.carve_sphere([0.0, 0.05, 0.0], 0.012, labels=bad)


def test_cut_splits_a_box_into_two_bodies_that_keep_the_mass():
    # A box of 8 voxels of 1 cm, corner at the origin; a blade in the plane x = 3.5 cm (the
    # centres of the layer i = 3) parked across the whole box takes that layer (64 voxels); the
    # box is then two bodies: x in [0, 3) cm (192 voxels, keeps the name) and [4, 8) cm (256):
    # the larger is i >= 4, so "body0" is that one and "body0-2" the other.
    body = gradel.Body.from_shape("box", 8)
    sim = gradel.Simulation(body, gravity=[0, 0, 0], dt=1e-4)
    sim.velocities[:] = [0.0, 0.2, 0.0]
    mass = sim.masses.sum()
    assert sim.cut([0.035, 0.04, 0.04], [[0, 1, 0], [0, 0, 1]], [0.1, 0.1]) == 64
    assert sim.num_bodies == 2 and sim.body_names == ["body0", "body0-2"]
    assert sim.masses.sum() == pytest.approx(mass - 64 * 1000 * 0.01 ** 3, rel=1e-12)
    assert sim.body_positions(0)[:, 0].min() == pytest.approx(0.04)
    assert sim.body_positions(1)[:, 0].max() == pytest.approx(0.03)
    assert np.allclose(sim.velocities, [0.0, 0.2, 0.0])
    assert sim.metrics()["removed_voxels"] == 64
    sim.step(10)
    assert np.isfinite(sim.positions).all()
    for bad in ([[0, 0], [[0, 1, 0], [0, 0, 1]], [0.1, 0.1]], [[0, 0, 0], [[0, 1, 0], [0, 1, 1]], [0.1, 0.1]],
                [[0, 0, 0], [[0, 1, 0], [0, 0, 1]], [0.1, -1]]):
        with pytest.raises(ValueError):
            sim.cut(*bad)


def test_carve_cylinder_bores_exactly_the_voxels_it_holds():
    # A box of 8 voxels of 1 cm at rest, corner at the origin. A rod of radius 1.7 cm along z
    # through (4, 4) cm holds the voxel columns whose centres lie within 1.7 cm of its axis: the
    # 2 x 2 around it (0.71 cm) and the 8 beside those (1.58 cm), not the diagonal ones (2.12 cm),
    # over all 8 layers: 96 voxels.
    body = gradel.Body.from_shape("box", 8)
    sim = gradel.Simulation(body, gravity=[0, 0, 0], dt=1e-4)
    mass = sim.masses.sum()
    assert sim.carve_cylinder([0.04, 0.04, 0.04], [0, 0, 3], 0.017, 0.05) == 96
    assert sim.masses.sum() == pytest.approx(mass - 96 * 1000 * 0.01 ** 3, rel=1e-12)
    assert sim.metrics()["removed_voxels"] == 96
    assert sim.carve_cylinder([0.04, 0.04, 0.04], [0, 0, 1], 0.012, 0.015) == 0  # the bore is empty already
    # A short rod along x through the voxel row at y = z = 1.5 cm (its neighbours 1 cm away, outside
    # the radius of 0.8 cm), caps at 1.3 and 6.7 cm: the 6 centres 1.5 ... 6.5 cm.
    assert sim.carve_cylinder([0.04, 0.015, 0.015], [1, 0, 0], 0.008, 0.027) == 6
    for bad in ([[0, 0], [0, 0, 1], 0.01, 0.01], [[0, 0, 0], [0, 0, 0], 0.01, 0.01],
                [[0, 0, 0], [0, 0, 1], -1, 0.01], [[0, 0, 0], [0, 0, 1], 0.01, float("nan")]):
        with pytest.raises(ValueError):
            sim.carve_cylinder(*bad)
