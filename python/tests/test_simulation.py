"""Simulations stepped from Python: the same bits as the command line, zero-copy views and
their rule, contacts, measurements on a trigger, checkpoints, Ctrl-C, errors."""

from __future__ import annotations

import os
import signal
import subprocess
import threading

import numpy as np
import pytest

import rheodem
from conftest import SMALL


def state(sim: rheodem.Simulation) -> dict:
    """Copies of the arrays that a continuation must reproduce, in id order."""
    order = np.argsort(sim.ids)
    return {
        "positions": sim.positions[order].copy(),
        "velocities": sim.velocities[order].copy(),
        "angular_velocities": sim.angular_velocities[order].copy(),
        "forces": sim.forces[order].copy(),
    }


def assert_same_bits(a: dict, b: dict) -> None:
    for key in a:
        assert a[key].tobytes() == b[key].tobytes(), key


def test_a_python_run_equals_the_command_line_run_bit_for_bit(tmp_path, cli, small_scenario):
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    out = tmp_path / "cli"
    subprocess.run(
        [cli, "run", path, "--out", out, "--threads", "1", "--quiet"], check=True
    )
    sim = rheodem.Simulation(small_scenario, threads=1)
    sim.run()
    assert sim.step_count == 400 == sim.end_step
    from_cli = rheodem.Simulation.from_run(out)
    assert from_cli.step_count == 400 and from_cli.threads == 1
    assert sim.time == from_cli.time
    assert_same_bits(state(sim), state(from_cli))
    # The run directory of `run_scenario` (the same driver from Python) holds it too.
    summary = rheodem.run_scenario(path, tmp_path / "py", threads=1)
    assert summary["status"] == "completed" and summary["steps_done"] == 400
    assert_same_bits(state(sim), state(rheodem.Simulation.from_run(tmp_path / "py")))


def test_views_share_the_simulations_memory_and_are_read_only(small_scenario):
    sim = rheodem.Simulation(small_scenario, threads=1)
    sim.run(steps=5)
    n = len(sim)
    for name, shape, dtype in [
        ("positions", (n, 3), np.float64),
        ("velocities", (n, 3), np.float64),
        ("angular_velocities", (n, 3), np.float64),
        ("forces", (n, 3), np.float64),
        ("torques", (n, 3), np.float64),
        ("radii", (n,), np.float64),
        ("masses", (n,), np.float64),
        ("ids", (n,), np.uint32),
        ("parts", (n,), np.uint16),
        ("species", (n,), np.uint16),
    ]:
        a, b = getattr(sim, name), getattr(sim, name)
        assert a.shape == shape and a.dtype == dtype, name
        # The same memory across two reads within a step: no copy was made.
        assert a.__array_interface__["data"][0] == b.__array_interface__["data"][0], name
        assert not a.flags.writeable, name
        with pytest.raises(ValueError):
            a[0] = 0
    assert sorted(sim.ids.tolist()) == list(range(n))
    # Masses follow from the radii and the density.
    np.testing.assert_allclose(sim.masses, 2000.0 * 4 / 3 * np.pi * sim.radii**3, rtol=1e-12)


def test_a_view_keeps_the_state_of_its_step_and_the_simulation_moves_on(small_scenario):
    sim = rheodem.Simulation(small_scenario, threads=1)
    sim.run(steps=3)
    held = sim.positions
    before = held.copy()
    sim.run(steps=20)
    # The view still shows the step it was taken at, in memory the simulation let go.
    assert held.tobytes() == before.tobytes()
    now = sim.positions
    assert not np.shares_memory(held, now)
    assert (now != before).any()
    # Without a live view a step copies nothing: the simulation keeps its memory.
    address = now.__array_interface__["data"][0]
    del now
    sim.step()
    assert sim.positions.__array_interface__["data"][0] == address
    # A view outlives its simulation.
    del sim
    assert held.tobytes() == before.tobytes()


def test_contact_forces_add_up_to_the_forces_of_the_step(small_scenario):
    sim = rheodem.Simulation(small_scenario, threads=1)
    for steps in (0, 9):
        sim.run(steps=steps)
        c = sim.contacts()
        m = len(c["i"])
        assert m > 0
        for key in ("branch", "normal", "force", "normal_force", "tangential_force"):
            assert c[key].shape == (m, 3)
        slot = np.empty(len(sim), dtype=np.int64)
        slot[sim.ids] = np.arange(len(sim))
        total = np.zeros((len(sim), 3))
        np.add.at(total, slot[c["i"]], c["force"])
        pairs = ~c["wall"]
        np.add.at(total, slot[c["j"][pairs]], c["force_on_j"][pairs])
        scale = np.abs(sim.forces).max()
        assert np.abs(total - sim.forces).max() < 1e-10 * scale
        # The split into normal and tangential parts.
        np.testing.assert_allclose(c["normal_force"] + c["tangential_force"], c["force"])
        assert np.abs(np.einsum("ij,ij->i", c["tangential_force"], c["normal"])).max() < (
            1e-12 * scale
        )
        # Overlaps from the branch vectors: a_i + a_j - |branch|.
        radius = np.empty(len(sim))
        radius[sim.ids] = sim.radii
        overlap = radius[c["i"]] + radius[c["j"]] - np.linalg.norm(c["branch"], axis=1)
        np.testing.assert_allclose(c["overlap"][pairs], overlap[pairs], atol=1e-15)
        assert not c["bridge"].any()
    assert sim.observables()["contacts"] == int((c["overlap"] > 0).sum())


def test_a_measurement_fires_at_its_steps_and_times(small_scenario):
    sim = rheodem.Simulation(small_scenario, threads=1)
    steps, times = [], []
    handle = sim.attach(lambda s: steps.append(s.step_count), every=7)
    sim.attach(lambda s: times.append(s.time), dt=10 * sim.dt)
    sim.run(steps=35)
    assert steps == [7, 14, 21, 28, 35]
    # At the first step whose time (the sum of the steps) reaches each multiple of dt.
    period, t, k, expected = 10 * sim.dt, 0.0, 1, []
    for _ in range(35):
        t += sim.dt
        if t >= k * period:
            expected.append(t)
            while k * period <= t:
                k += 1
    assert times == expected and len(times) == 3
    sim.detach(handle)
    sim.run(steps=10)
    assert steps == [7, 14, 21, 28, 35]
    with pytest.raises(ValueError, match="handle"):
        sim.detach(handle)
    # A period equal to the time step fires at (nearly) every step and never twice at one.
    fired = []
    every_step = sim.attach(lambda s: fired.append(s.step_count), dt=sim.dt)
    sim.run(steps=20)
    sim.detach(every_step)
    assert 18 <= len(fired) <= 20 and len(set(fired)) == len(fired)
    # The measurement reads the state; it cannot step it.
    sim.attach(lambda s: s.step(), every=1)
    with pytest.raises(rheodem.RunError, match="cannot step"):
        sim.run(steps=1)


def test_a_measurement_sees_the_state_of_its_step(small_scenario):
    reference = rheodem.Simulation(small_scenario, threads=1)
    reference.run(steps=12)
    expected = state(reference)
    sim = rheodem.Simulation(small_scenario, threads=1)
    seen = {}
    sim.attach(lambda s: seen.setdefault(s.step_count, state(s)), every=12)
    sim.run(steps=20)
    assert list(seen) == [12]
    assert_same_bits(seen[12], expected)


def test_checkpoint_and_load_continue_bit_identically(tmp_path, small_scenario):
    sim = rheodem.Simulation(small_scenario, threads=2)
    sim.run(steps=25)
    sim.checkpoint(tmp_path / "state.bin")
    sim.run(steps=40)
    loaded = rheodem.Simulation.load(tmp_path / "state.bin")
    assert loaded.threads == 2 and loaded.step_count == 25
    loaded.run(steps=40)
    assert loaded.time == sim.time
    assert_same_bits(state(loaded), state(sim))


def test_ctrl_c_stops_between_steps_and_the_run_goes_on(small_scenario):
    sim = rheodem.Simulation(small_scenario, threads=1)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        sim.run(steps=10**9)
    timer.join()
    stopped = sim.step_count
    assert 0 < stopped < 10**9
    sim.run(steps=5)
    assert sim.step_count == stopped + 5


def test_a_simulation_running_in_another_thread_is_in_use():
    sim = rheodem.Simulation.standard_problem(threads=1)
    started = threading.Event()
    sim.attach(lambda s: started.set(), every=500)
    runner = threading.Thread(target=sim.run, kwargs={"steps": 3000})
    runner.start()
    assert started.wait(timeout=60)
    with pytest.raises(rheodem.RunError, match="in use by another thread"):
        while True:  # until a read falls into a stretch of steps (almost at once)
            sim.positions
    runner.join()
    assert sim.step_count == 3000


def test_errors_name_the_key_and_the_allowed_range(small_scenario):
    with pytest.raises(rheodem.ScenarioError) as e:
        rheodem.Simulation(
            rheodem.Scenario.from_toml(SMALL.replace("density = 2000.0", "density = -1.0")),
            threads=1,
        )
    assert e.value.key == "species[0].density"
    assert e.value.value == "-1"
    assert "positive" in e.value.allowed
    assert "species[0].density" in str(e.value)
    with pytest.raises(rheodem.ScenarioError, match="densty"):
        rheodem.Scenario.from_toml(SMALL.replace("density = 2000.0", "densty = 2000.0"))
    with pytest.raises(ValueError, match="threads = 0"):
        rheodem.Simulation(small_scenario, threads=0)
    sim = rheodem.Simulation(small_scenario, threads=1)
    with pytest.raises(ValueError, match="not both"):
        sim.run(steps=1, duration=1.0)
    with pytest.raises(ValueError, match="every = 0"):
        sim.attach(print, every=0)
    with pytest.raises(rheodem.RunError, match="checkpoint"):
        rheodem.Simulation.load(__file__)
