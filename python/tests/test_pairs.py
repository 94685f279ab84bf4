"""A case of several contact pairs: each pair's result by name, the case's status the worst
pair's, a body's surface in each of its pairs, and the command line's numbers.

Three blocks stacked (tests/fixtures/three_blocks_2d.msh): `upper` pressed down onto `middle`,
which floats (held only by its two contacts) on `lower`, every side held in x. The exact
answer is uniform uniaxial strain: the same contact force per unit thickness on both
interfaces, sigma = d / sum_i (1 / M_i), with the P-wave modulus M = E (1 - nu) / ((1 + nu)
(1 - 2 nu)) of each block of height 1.
"""

import pickle

import pytest

import internodes
from conftest import REPO, comparable, read_summary

MSH = REPO / "tests" / "fixtures" / "three_blocks_2d.msh"
PUSH = 0.01
NU = 0.3
MODULI = {"upper": 500.0, "middle": 3000.0, "lower": 1000.0}
PAIRS = {"upper-middle": (["upper", "middle"], ["upper_contact", "middle_top"]),
         "middle-lower": (["middle", "lower"], ["middle_bottom", "lower_contact"])}


def p_wave(e):
    return e * (1 - NU) / ((1 + NU) * (1 - 2 * NU))


SIGMA = PUSH / sum(1 / p_wave(e) for e in MODULI.values())


def table(tolerance=1e-6, pairs=PAIRS, **top):
    """The three-block case's keys (pairs unnamed: their default names are PAIRS' keys)."""
    bodies = []
    for name, e in MODULI.items():
        dirichlet = [{"group": f"{name}_sides", "ux": 0.0}]
        if name == "lower":
            dirichlet.append({"group": "lower_base", "uy": 0.0})
        if name == "upper":
            dirichlet.append({"group": "upper_top", "uy": -PUSH})
        bodies.append({"name": name, "youngs_modulus": e, "poisson_ratio": NU,
                       "dirichlet": dirichlet})
    contacts = [{"bodies": b, "surfaces": s, "penetration_tolerance": tolerance}
                for b, s in pairs.values()]
    return {"mesh": str(MSH), **top, "contact": contacts, "body": bodies}


def toml_file(folder, keys):
    """`keys` (as `table` gives them) as a case file with [[contact]] tables."""
    def value(v):
        return f'"{v}"' if isinstance(v, str) else repr(v).replace("'", '"')

    lines = [f"{k} = {value(v)}" for k, v in keys.items() if k not in ("contact", "body")]
    for pair in keys["contact"]:
        lines += ["", "[[contact]]"] + [f"{k} = {value(v)}" for k, v in pair.items()]
    for body in keys["body"]:
        lines += ["", "[[body]]"]
        lines += [f"{k} = {value(v)}" for k, v in body.items() if k != "dirichlet"]
        for condition in body["dirichlet"]:
            lines += ["", "[[body.dirichlet]]"] + [f"{k} = {value(v)}" for k, v in condition.items()]
    path = folder / "three_blocks.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def stacked():
    return internodes.solve(internodes.Case.from_dict(table(), name="three_blocks"))


def test_the_case_names_its_pairs():
    case = internodes.Case.from_dict(table())
    assert case.pairs == ["upper-middle", "middle-lower"]
    assert repr(case) == "Case('case', bodies=[\"upper\", \"middle\", \"lower\"], pairs=2)"
    named = table()
    named["contact"][0]["name"] = "top"
    assert internodes.Case.from_dict(named).pairs == ["top", "middle-lower"]
    alone = table()
    del alone["contact"]
    alone["body"][1]["dirichlet"].append({"group": "middle_bottom", "uy": 0.0})
    assert internodes.Case.from_dict(alone).pairs == []


def test_each_pair_s_force_is_the_exact_one(stacked):
    assert list(stacked.contacts) == ["upper-middle", "middle-lower"]
    assert stacked.status == "converged" and stacked.exit_code == 0
    summaries = stacked.summary["contacts"]
    assert "contact" not in stacked.summary
    assert [s["name"] for s in summaries] == list(PAIRS)
    for (name, pair), summary in zip(stacked.contacts.items(), summaries):
        assert isinstance(pair, internodes.ContactResult)
        assert pair.name == name and pair.status == "converged"
        assert (pair.solved, pair.accurate, pair.exit_code) == (True, True, 0)
        assert [pair.primary, pair.secondary] in (PAIRS[name][0], PAIRS[name][0][::-1])
        assert pair.summary == summary
        assert repr(pair).startswith(f"ContactResult('{name}', status=converged")
        # The force per unit thickness (the blocks are 1 wide), from the summary and the step.
        assert len(pair.steps) == 1 and pair.steps[0].status == "converged"
        for force in (summary["force_primary"][1], pair.steps[0].force_primary[1]):
            assert abs(abs(force) - SIGMA) <= 1e-7 * SIGMA, (name, force, SIGMA)


def test_one_pair_s_steps_or_surface_is_not_the_case_s(stacked):
    with pytest.raises(ValueError, match=r"2 contact pairs .*result\.contacts\[name\]\.steps"):
        stacked.steps
    middle = stacked.bodies["middle"]
    assert list(middle.surfaces) == ["upper-middle", "middle-lower"]
    assert all(isinstance(s, internodes.SurfaceResult) for s in middle.surfaces.values())
    # Its top is pressed by `upper`, its bottom by `lower`: both surfaces fully in contact.
    assert all(s.active.all() for s in middle.surfaces.values())
    with pytest.raises(ValueError, match=r"body 'middle' is in 2 contact pairs .*surfaces"):
        middle.surface
    # A body in one pair keeps its one surface.
    upper = stacked.bodies["upper"]
    assert list(upper.surfaces) == ["upper-middle"]
    assert upper.surface is upper.surfaces["upper-middle"]


def test_the_module_gives_the_cli_s_summary(cli, tmp_path, stacked):
    case_file = toml_file(tmp_path, table())
    code, stderr = cli(case_file, tmp_path / "cli")
    assert code == 0, stderr
    theirs = read_summary(tmp_path / "cli")
    from_file = internodes.solve(internodes.Case.from_toml(case_file))
    assert comparable(from_file.summary) == comparable(theirs)
    # The same keys in code: the same numbers (the case's name aside).
    assert comparable(stacked.summary, ["case"]) == comparable(theirs, ["case"])
    from_file.write(tmp_path / "py")
    assert comparable(read_summary(tmp_path / "py")) == comparable(theirs)
    written = sorted(p.name for p in (tmp_path / "py").iterdir())
    assert written == sorted(p.name for p in (tmp_path / "cli").iterdir())


def test_the_typed_summary_describes_a_summary_of_several_pairs(stacked):
    typed = pytest.importorskip("internodes.summary")
    conforms = pytest.importorskip("test_export").conforms
    conforms(stacked.summary, typed.Summary)


def test_the_status_is_the_worst_pair_s():
    # `upper` pulled up off `middle`, which is held at its base: one pair opens, one touches
    # (without a force); a pair that converged outranks one without contact.
    opened = table()
    opened["body"][0]["dirichlet"][1]["uy"] = PUSH
    opened["body"][1]["dirichlet"].append({"group": "middle_bottom", "uy": 0.0})
    result = internodes.solve(internodes.Case.from_dict(opened))
    statuses = {name: pair.status for name, pair in result.contacts.items()}
    assert statuses == {"upper-middle": "no-contact", "middle-lower": "converged"}
    assert (result.status, result.exit_code) == ("converged", 0)
    # `middle` held at its sides and pushed down between the two (its first active sets are
    # not the answer: two iterations) with one active-set iteration allowed (the pairs share
    # the loop, so they share its cap): no pair solved, and the case's verdict names the first.
    capped = table()
    capped["body"][1]["dirichlet"][0]["uy"] = -0.3 * PUSH
    for pair in capped["contact"]:
        pair["max_iterations"] = 1
    result = internodes.solve(internodes.Case.from_dict(capped))
    assert [pair.status for pair in result.contacts.values()] == ["iteration-limit"] * 2
    assert [pair.exit_code for pair in result.contacts.values()] == [2, 2]
    assert (result.status, result.exit_code, result.solved) == ("iteration-limit", 2, False)
    with pytest.raises(internodes.NotSolvedError, match="pair 'upper-middle'"):
        result.raise_for_status()


def test_a_pair_of_an_unknown_body_is_refused():
    bad = table(pairs={**PAIRS, "x": (["middle", "base"], ["middle_bottom", "lower_contact"])})
    with pytest.raises(internodes.InputError, match="'base'"):
        internodes.Case.from_dict(bad)


def test_a_case_of_several_pairs_pickles_with_its_load_steps():
    case = internodes.Case.from_dict(table(load_steps=[0.5, 1.0]))
    again = pickle.loads(pickle.dumps(case))
    assert (again.pairs, again.load_steps) == (case.pairs, [0.5, 1.0])


def test_a_case_without_contact_has_no_pairs():
    alone = table()
    del alone["contact"]
    alone["body"][1]["dirichlet"].append({"group": "middle_bottom", "uy": 0.0})
    result = internodes.solve(internodes.Case.from_dict(alone))
    assert (result.status, result.contacts, result.steps) == (None, {}, [])
    assert result.bodies["middle"].surfaces == {} and result.bodies["middle"].surface is None


def test_to_meshio_holds_every_surface_of_a_body_as_the_files_do(stacked, tmp_path):
    pytest.importorskip("meshio")
    h5py = pytest.importorskip("h5py")
    stacked.write(tmp_path)
    with h5py.File(tmp_path / "solution.h5", "r") as f:
        written = {key: f["fields"][key][()] for key in ("contact_pressure", "normal_gap")}
    meshes = internodes.to_meshio(stacked)
    offset = 0
    for name, body in stacked.bodies.items():
        n = len(body.coordinates)
        for key, values in written.items():
            assert (meshes[name].point_data[key] == values[offset:offset + n].ravel()).all(), \
                (name, key)
        offset += n
    middle = meshes["middle"].point_data["contact_pressure"]
    for surface in stacked.bodies["middle"].surfaces.values():
        assert (middle[surface.nodes.astype(int)] == surface.pressure).all()
        assert abs(surface.pressure.mean() - SIGMA) < 1e-6 * SIGMA


def test_a_study_of_several_pairs_is_refused(tmp_path):
    keys = table()
    keys["mesh"] = str(REPO / "geo" / "three_blocks_2d.geo")
    with pytest.raises(internodes.InputError, match="one contact pair, and the case has 2"):
        internodes.study(internodes.Case.from_dict(keys), "level", [0, 1], output=tmp_path)
