#!/usr/bin/python3
"""gradel from Python: a bone cut out of a synthetic CT scan by a threshold is dropped on the
floor, a sphere manipulator driven from this script pushes it, and the state is read as numpy
arrays every frame.

    PYTHONPATH=build/python /usr/bin/python3 examples/python_example.py [--duration 1.0]

(build/ is what scripts/setup builds; run from the repository root.)
"""
import argparse
import os

import numpy as np

import gradel

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds")
    args = parser.parse_args()

    # 1. Volumes: a file read straight into a boolean numpy array (no copy) ...
    ct = os.path.join(ROOT, "samples", "ct.nrrd")
    bone = gradel.load_volume(ct, threshold=300)     # Hounsfield units: bone only
    limb = gradel.load_volume(ct, threshold=-300)    # soft tissue and bone
    print(f"ct.nrrd {bone.shape}: {bone.sum()} bone voxels at 300 HU, {limb.sum()} at -300 HU")

    # ... a body from that array (or Body.from_file / Body.from_shape).
    body = gradel.Body.from_array(bone, voxel_size=0.005)
    print(body)

    # 2. Material, layout and integrator are fixed when the simulation is built.
    sim = gradel.Simulation(
        body, layout="gradational", youngs_modulus=2e5, density=1100, integrator="symplectic",
        damping=3.0, gravity=[0, -9.81, 0], position=[-0.1, 0.05, -0.1],
        domain_min=[-0.4, 0.0, -0.4], domain_max=[0.4, 1.0, 0.4], restitution=0.3, friction=0.4)
    print(f"{sim.num_elements} elements, {sim.num_vertices} vertices, dt = {sim.dt:.3g} s")

    # 3. A manipulator this script moves: it sweeps in along +x at floor height.
    pusher = sim.add_manipulator("sphere", radius=0.04, position=[-0.35, 0.05, 0.0], friction=0.2)

    positions = sim.positions  # a live (N, 3) view of the world's memory: no copy per frame
    frame = 1.0 / 30.0
    t = 0.0
    while t < args.duration - 1e-9:
        t = min(t + frame, args.duration)
        x = -0.35 + 0.5 * min(t, 0.8)  # 0.5 m/s for 0.8 s, then rest
        sim.move_manipulator(pusher, [x, 0.05, 0.0], [0.5 if t < 0.8 else 0.0, 0, 0])
        sim.advance_to(t)
        centre = positions.mean(axis=0)
        print(f"t = {sim.time:5.3f} s  centre = ({centre[0]:+.3f}, {centre[1]:+.3f}, {centre[2]:+.3f}) m  "
              f"max von Mises stress = {sim.stress.max():.1f} Pa")

    vertices, triangles, normals = sim.surface("smooth")
    m = sim.metrics()
    print(f"surface: {len(vertices)} vertices, {len(triangles)} triangles; "
          f"kinetic energy {m['kinetic_energy']:.3g} J, max penetration {m['max_penetration']:.2g} m")
    assert np.isfinite(positions).all()


if __name__ == "__main__":
    main()
