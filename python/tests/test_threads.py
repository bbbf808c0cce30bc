"""Thread-safety contract, Ctrl-C and refused values of the Python API (docs/io.md, issue 15)."""
import math
import signal
import threading
import time

import numpy as np
import pytest

import gradel


def small(**kw):
    return gradel.Simulation(gradel.Body.from_shape("sphere", 6), gravity=[0, 0, 0], damping=1.0, **kw)


def test_concurrent_steps_and_mutations_are_serialised():
    sim = small()
    n_threads, calls, per_call = 3, 100, 20
    errors = []

    def stepper():
        try:
            for _ in range(calls):
                sim.step(per_call)
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    def mutator():
        try:
            for k in range(150):
                i = sim.add_manipulator("sphere", radius=0.002, position=[1.0 + k, 1.0, 1.0])
                sim.move_manipulator(i, [2.0 + k, 1.0, 1.0])
                sim.metrics()
                _ = sim.stress, sim.manipulator_positions, sim.state_hash
                sim.velocities = np.zeros((sim.num_vertices, 3))
        except Exception as e:  # pragma: no cover
            errors.append(e)

    threads = [threading.Thread(target=stepper) for _ in range(n_threads)] + [threading.Thread(target=mutator) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert round(sim.time / sim.dt) == n_threads * calls * per_call  # no lost step
    assert len(sim.manipulator_positions) == 300
    assert np.all(np.isfinite(sim.positions))


def test_ctrl_c_interrupts_a_long_advance_to():
    sim = small(dt=1e-9)  # 1e7 steps to 0.01 s: minutes
    timer = threading.Timer(0.3, lambda: signal.raise_signal(signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        sim.advance_to(0.01)
    timer.join()
    assert time.monotonic() - start < 5
    assert 0 < sim.time < 0.01  # the steps done so far are kept
    sim.step(2)  # still usable


@pytest.mark.parametrize("t", [math.inf, math.nan, 1e300])
def test_absurd_targets_are_refused(t):
    sim = small()
    with pytest.raises(ValueError, match="t:"):
        sim.advance_to(t)
    assert sim.time == 0


def test_tiny_dt_target_is_refused_by_step_count():
    sim = small(dt=1e-300)
    with pytest.raises(ValueError, match="max_steps"):
        sim.advance_to(1.0)
    with pytest.raises(ValueError, match="n:"):
        sim.step(-1)


def test_non_finite_state_is_refused_and_reported_as_nan():
    sim = small()
    p = sim.positions.copy()
    p[2, 1] = math.nan
    with pytest.raises(ValueError, match="positions"):
        sim.positions = p
    with pytest.raises(ValueError, match="velocities"):
        sim.velocities = np.full((sim.num_vertices, 3), math.inf)
    assert np.all(np.isfinite(sim.positions))
    sim.positions[2, 1] = math.nan  # written into the view: not caught on write ...
    m = sim.metrics()
    assert math.isnan(m["min_element_det"]) and math.isnan(m["max_penetration"])
    with pytest.raises(ValueError, match="positions: vertex 2"):
        sim.step()  # ... but refused before it can spread
    sim.positions = sim.rest_positions
    sim.step()
    assert math.isfinite(sim.metrics()["kinetic_energy"])


BOX = dict(domain_min=[-1, -1, -1], domain_max=[1, 1, 1])


@pytest.mark.parametrize(
    "kw, field",
    [
        (dict(threads=0), "threads"),
        (dict(threads=-1), "threads"),
        (dict(threads=100000), "threads"),
        (dict(restitution=5, **BOX), "restitution"),
        (dict(friction=-1, **BOX), "friction"),
        (dict(friction=math.nan, **BOX), "friction"),
        (dict(domain_min=[1, 1, 1], domain_max=[-1, -1, -1]), "max"),
        (dict(damping=-1), "damping"),
        (dict(youngs_modulus=-5), "youngs_modulus"),
        (dict(dt_fraction=2), "dt_fraction"),
    ],
)
def test_settings_checked_like_the_scene_reader(kw, field):
    with pytest.raises(ValueError, match=field):
        gradel.Simulation(gradel.Body.from_shape("sphere", 4), **kw)


@pytest.mark.parametrize("kw, field", [(dict(restitution=5), "restitution"), (dict(friction=-1), "friction"),
                                       (dict(friction=math.nan), "friction"), (dict(radius=-1), "radius")])
def test_manipulator_settings_checked(kw, field):
    sim = small()
    with pytest.raises(ValueError, match=field):
        sim.add_manipulator("sphere", **kw)
    assert len(sim.manipulator_positions) == 0
