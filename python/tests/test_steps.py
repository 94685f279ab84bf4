"""Every load step is reachable (`Result.steps`), and `raise_for_status()` fails on any step that
failed, not only on the last one."""

import numpy as np
import pytest

import internodes
from conftest import REPO

MESH = REPO / "tests" / "fixtures" / "half_disc_on_block.msh"


def case(load_steps, disc_top=None, **contact):
    """The half-disc pressed onto the block, its top held by `disc_top` (default: pushed down by
    0.02); `contact`: more settings of the pair."""
    disc_top = disc_top or {"dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -0.02}]}
    return internodes.Case.from_dict({
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"],
                    "load_steps": load_steps, **contact},
        "body": [{"name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3, **disc_top},
                 {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "block_base", "ux": 0.0, "uy": 0.0}]}]})


def test_each_step_has_its_own_record_as_in_the_summary():
    result = internodes.solve(case([0.5, 1.0]), mesh=internodes.Mesh.from_msh(MESH))
    steps, records = result.steps, result.summary["contact"]["steps"]
    assert [s.step for s in steps] == [1, 2] and [s.load_factor for s in steps] == [0.5, 1.0]
    for step, record in zip(steps, records):
        assert step.status == record["status"] and step.accurate == record["accurate"]
        assert step.failed_checks == record["failed_checks"]
        assert np.array_equal(step.force_primary, record["force_primary"])
        assert np.array_equal(step.force_secondary, record["force_secondary"])
        assert step.iterations == record["iterations"] and step.hertz_a == record["hertz_a"]
    # Half the approach, about half the force (Hertz: a little less than linear in 2D).
    assert 0.3 < steps[0].force_primary[1] / steps[1].force_primary[1] < 0.5
    assert steps[-1].status == result.status
    result.raise_for_status()
    assert "Step(1, load_factor=0.5, status=converged" in repr(steps[0])


def test_a_failed_earlier_step_fails_raise_for_status():
    # At 1% of the approach the contact zone spans too few spacings: that step's accuracy
    # report fails its resolution check, while the last step, the answer, passes.
    result = internodes.solve(case([0.01, 1.0]), mesh=internodes.Mesh.from_msh(MESH))
    first, last = result.steps
    assert (first.solved, first.accurate, first.failed_checks) == (True, False, ["resolution"])
    assert (last.solved, last.accurate) == (True, True)
    assert result.exit_code == 3  # the command line's status: the worst step's
    with pytest.raises(internodes.NotSolvedError,
                       match=r"accuracy report of an earlier one failed: step 1 \(load factor 0.01\): "
                             r"converged, failed: resolution"):
        result.raise_for_status()


def test_a_case_without_contact_has_no_steps():
    single = internodes.Case.from_dict({"body": [{
        "name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
        "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -0.02}]}]})
    assert internodes.solve(single, mesh=internodes.Mesh.from_msh(MESH)).steps == []


def test_each_step_gives_the_displacement_of_its_force():
    # The disc's top loaded by a force instead of a displacement: each step records the force
    # (ramped by the load factor) and how far the top moved under it, as the summary does.
    forced = case([0.5, 1.0], {"dirichlet": [{"group": "disc_top", "ux": 0.0}],
                               "force": [{"group": "disc_top", "fy": -5.0}]})
    result = internodes.solve(forced, mesh=internodes.Mesh.from_msh(MESH))
    result.raise_for_status()
    records = result.summary["contact"]["steps"]
    for step, record in zip(result.steps, records):
        assert step.forced == record["forced"]
        (moved,) = step.forced
        assert (moved["body"], moved["group"], moved["component"]) == ("disc", "disc_top", "y")
        assert moved["force"] == -5.0 * step.load_factor
        # The contact carries the whole force: nothing else holds the disc along y.
        assert np.isclose(step.force_primary[1], -moved["force"], rtol=1e-8)
    # Half the force, less than half the approach (Hertz: the approach grows faster than linear
    # in the force's square root, and the bulk adds a linear part).
    half, full = (s.forced[0]["displacement"] for s in result.steps)
    assert full < half < 0 and 0.4 < half / full < 0.6


def test_a_coulomb_pair_gives_each_step_its_tangential_answer():
    # The disc pushed down and sideways in two steps: friction against the slide.
    sideways = {"dirichlet": [{"group": "disc_top", "ux": 0.004, "uy": -0.02}]}
    frictional = case([0.5, 1.0], sideways, formulation="coulomb", friction_coefficient=0.3)
    result = internodes.solve(frictional, mesh=internodes.Mesh.from_msh(MESH))
    records = result.summary["contact"]["steps"]
    for step, record in zip(result.steps, records):
        assert step.friction is not None and record["friction"]["stick_nodes"] == step.friction["stick_nodes"]
        assert np.array_equal(step.friction["tangential_force"], record["friction"]["tangential_force"])
        # |Q| <= mu P: the Coulomb cone, summed over the nodes.
        assert np.linalg.norm(step.friction["tangential_force"]) <= 0.3 * step.friction["normal_force"] * (1 + 1e-9)
        assert step.friction["stick_nodes"] + step.friction["slip_nodes"] > 0
    # The friction on the disc opposes its slide (+x).
    assert result.steps[-1].friction["tangential_force"][0] < 0.0
    # Frictionless pairs have none.
    assert internodes.solve(case([1.0]), mesh=internodes.Mesh.from_msh(MESH)).steps[0].friction is None


def test_a_load_path_from_a_dict():
    # The disc's top pushed down along "press": a dict case takes [load_path] and `path` as a
    # case file does, and each step records its paths' factors.
    paths = {"dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -0.02, "path": "press"}]}
    table = {
        "load_path": {"press": [0.5, 1.0]},
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"]},
        "body": [{"name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3, **paths},
                 {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "block_base", "ux": 0.0, "uy": 0.0}]}]}
    along = internodes.Case.from_dict(table)
    assert along.load_path == {"press": [0.5, 1.0]} and along.load_steps == [1.0, 1.0]
    result = internodes.solve(along, mesh=internodes.Mesh.from_msh(MESH))
    result.raise_for_status()
    assert [s.path_factors for s in result.steps] == [{"press": 0.5}, {"press": 1.0}]
    records = result.summary["contact"]["steps"]
    assert [r["path_factors"] for r in records] == [{"press": 0.5}, {"press": 1.0}]
    # The same answer as load steps of the same factors.
    stepped = internodes.solve(case([0.5, 1.0]), mesh=internodes.Mesh.from_msh(MESH))
    for step, reference in zip(result.steps, stepped.steps):
        assert np.allclose(step.force_primary, reference.force_primary, rtol=1e-6)
    assert stepped.steps[0].path_factors == {}
    # A path the [load_path] does not have is an InputError naming it.
    table["body"][0]["dirichlet"][0]["path"] = "shear"
    with pytest.raises(internodes.InputError, match="no path 'shear'"):
        internodes.Case.from_dict(table)


def min_edge(body):
    """The shortest edge of the body's cells: at most the spacing of its contact surface."""
    points = body.coordinates[body.cells]
    edges = [np.linalg.norm(points[:, a] - points[:, b], axis=1)
             for a in range(points.shape[1]) for b in range(a)]
    return min(e.min() for e in edges)


def test_every_step_has_its_fields_and_equals_an_independent_solve_with_the_run_s_primary():
    mesh = internodes.Mesh.from_msh(MESH)
    result = internodes.solve(case([0.5, 1.0]), mesh=mesh)
    first, last = result.step_bodies(0), result.step_bodies(1)
    assert set(first) == set(last) == {"disc", "block"}
    # The last step's fields are `bodies`; -1 counts from the last; no third step.
    assert result.step_bodies(-1)["disc"] is result.bodies["disc"] is last["disc"]
    assert result.step_bodies(-2)["disc"].displacement.tolist() == first["disc"].displacement.tolist()
    with pytest.raises(IndexError, match="load step index 2 out of range: the result has 2"):
        result.step_bodies(2)
    # Each step's fields are its own: half the approach, about half the displacement.
    u_half, u_full = first["disc"].displacement, last["disc"].displacement
    assert 0.45 < np.abs(u_half).max() / np.abs(u_full).max() < 0.55
    for name in ["disc", "block"]:
        for key in ["strain", "stress", "von_mises"]:
            assert not np.array_equal(getattr(first[name], key), getattr(last[name], key)), key
        surface, last_surface = first[name].surface, last[name].surface
        assert np.array_equal(surface.nodes, last_surface.nodes)
        assert surface.active.sum() < last_surface.active.sum()
    # The force of step 1 is the contact traction of step 1's fields.
    assert first["disc"].surface.pressure.max() < last["disc"].surface.pressure.max()
    # docs/case-file.md: every step is solved with the run's primary; a step equals an
    # independent solve at its factor with that primary, to the loop's stopping precision
    # (every active node within 1e-5 spacings of the other surface).
    pair = result.contacts["disc-block"]
    alone = internodes.solve(case([0.5], primary=pair.primary), mesh=mesh)
    assert alone.contacts["disc-block"].primary == pair.primary
    for name in ["disc", "block"]:
        bound = 1e-5 * min_edge(alone.bodies[name])
        difference = np.abs(first[name].displacement - alone.bodies[name].displacement).max()
        assert difference <= bound, (name, difference, bound)
        assert np.array_equal(first[name].surface.active, alone.bodies[name].surface.active)


def test_a_case_without_contact_has_one_step_of_fields():
    single = internodes.Case.from_dict({"body": [{
        "name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
        "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -0.02}]}]})
    result = internodes.solve(single, mesh=internodes.Mesh.from_msh(MESH))
    assert result.step_bodies(0)["disc"] is result.bodies["disc"]
    with pytest.raises(IndexError, match="the result has 1 load step$"):
        result.step_bodies(1)


def test_to_meshio_exports_any_step():
    meshio = pytest.importorskip("meshio")
    result = internodes.solve(case([0.5, 1.0]), mesh=internodes.Mesh.from_msh(MESH))
    for k in [0, 1]:
        meshes = internodes.to_meshio(result, step=k)
        assert isinstance(meshes["disc"], meshio.Mesh)
        body = result.step_bodies(k)["disc"]
        assert np.array_equal(meshes["disc"].point_data["displacement"], body.displacement)
        assert np.array_equal(meshes["disc"].cell_data["stress"][0], body.stress.reshape(-1, 9))
    last = internodes.to_meshio(result)["disc"]
    assert np.array_equal(last.point_data["displacement"], result.bodies["disc"].displacement)


def test_auto_s_retry_is_the_run_s_so_a_step_differs_from_an_auto_solve_alone():
    # docs/case-file.md (load steps): the 3D hemisphere on its block, stepped 0.2 -> 1. Step 1
    # fails its secondary sag check with the block as primary, the last step passes: the run
    # keeps the block. Alone at 0.2, auto's answer is the untrusted one, and auto retries with
    # the sphere: a force 2.2% off the step's. With the run's primary named, it is the step's.
    tomllib = pytest.importorskip("tomllib")  # Python 3.11

    geo = REPO / "geo" / "hemisphere_on_block.geo"
    keys = tomllib.loads((REPO / "geo" / "hemisphere_on_block.toml").read_text())
    mesh = internodes.Mesh.from_geo(geo, keys.pop("geo_parameters"))
    keys["mesh"] = str(geo)

    def solve(**contact):
        return internodes.solve(
            internodes.Case.from_dict({**keys, "contact": {**keys["contact"], **contact}}), mesh=mesh)

    stepped = solve(load_steps=[0.2, 1.0])
    step = stepped.steps[0]
    assert stepped.contacts["sphere-block"].primary == "block"
    assert (step.failed_checks, stepped.steps[1].accurate) == (["secondary sag"], True)
    auto = solve(load_steps=[0.2])
    assert auto.contacts["sphere-block"].primary == "sphere" and auto.accurate
    named = solve(load_steps=[0.2], primary="block")
    assert np.array_equal(named.steps[0].force_primary, step.force_primary)
    assert np.array_equal(named.bodies["sphere"].displacement,
                          stepped.step_bodies(0)["sphere"].displacement)
    off = abs(np.linalg.norm(auto.steps[0].force_primary) / np.linalg.norm(step.force_primary) - 1)
    assert off > 0.01, off
