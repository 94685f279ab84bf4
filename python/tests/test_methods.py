"""The enforcement is one key: `method = "penalty"` beside the default INTERNODES, the same `Case`,
`solve` and results, for frictionless and Coulomb pairs alike."""

import numpy as np

import internodes
from conftest import REPO

MESH = REPO / "tests" / "fixtures" / "half_disc_on_block.msh"


def case(**contact):
    """The half-disc pushed down by 0.02 and sideways by `shift` onto the block."""
    shift = contact.pop("shift", 0.0)
    return internodes.Case.from_dict({
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"],
                    "primary": "disc", **contact},
        "body": [{"name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "disc_top", "ux": shift, "uy": -0.02}]},
                 {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "block_base", "ux": 0.0, "uy": 0.0}]}]})


def test_the_penalty_method_is_one_key_and_tends_to_internodes():
    mesh = internodes.Mesh.from_msh(MESH)
    for law in [{}, {"formulation": "coulomb", "friction_coefficient": 0.3, "shift": 0.002}]:
        exact = internodes.solve(case(**law), mesh=mesh)
        exact.raise_for_status()
        assert "penalty_stiffness" not in exact.summary["contact"]
        stiff = internodes.solve(case(method="penalty", penalty=1e8, **law), mesh=mesh)
        soft = internodes.solve(case(method="penalty", **law), mesh=mesh)  # the default, 100
        for penalized in (stiff, soft):
            penalized.raise_for_status()
            record = penalized.summary["contact"]
            assert record["settings"]["method"] == "penalty" and record["penalty_stiffness"] > 0
            assert "penalty overlap" in [c["name"] for c in record["accuracy"]["indicators"]]
        # The stiff penalty is INTERNODES to its overlap; the soft one lets the disc sink in and
        # carries less.
        force = {name: np.array(result.summary["contact"]["force_primary"])
                 for name, result in [("exact", exact), ("stiff", stiff), ("soft", soft)]}
        assert np.allclose(force["stiff"], force["exact"], rtol=1e-6, atol=1e-6)
        assert force["soft"][1] < force["exact"][1] * (1 - 1e-4)
