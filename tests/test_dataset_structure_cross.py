"""A dataset spec that crosses structure = [rigid, flexible] with the flexible structure's fields: each field
applies to the flexible runs only; without a structure factor a structure field on a rigid base is refused."""

from __future__ import annotations

import dataclasses

import pytest

from twin.config.structure import StructureConfig
from twin.dataset.design import plan
from twin.dataset.spec import SpecError, load_spec

SPEC = """
[dataset]
name = "cross"
seed = 1
[base]
test = 3
duration_s = 0.05
[design]
kind = "grid"
[factors]
{factors}
[outputs]
truth = ["accel"]
instrumented = false
"""


def _spec(tmp_path, factors: str):
    p = tmp_path / "cross.toml"
    p.write_text(SPEC.format(factors=factors))
    return load_spec(p)


def test_structure_fields_apply_to_the_flexible_runs_only(tmp_path):
    runs = plan(_spec(tmp_path, 'structure = ["rigid", "flexible"]\nbending_damping_ratio = [0.02, 0.03]\n'
                                '"structure.frame_damping_ratio" = [0.04]'))
    assert len(runs) == 4
    defaults = {f.name: f.default for f in dataclasses.fields(StructureConfig)}
    for r in runs:
        st = r.config.structure
        if r.factors["structure"] == "flexible":
            assert st.mode == "flexible" and st.bending_damping_ratio == r.factors["bending_damping_ratio"]
            assert st.frame_damping_ratio == 0.04
        else:
            assert st.mode == "rigid"
            assert all(getattr(st, k) == v for k, v in defaults.items() if k != "mode")
    assert len({r.run_id for r in runs}) == 4  # the two rigid runs differ in their seeds


def test_a_structure_field_without_the_structure_factor_is_still_refused_on_a_rigid_base(tmp_path):
    with pytest.raises(SpecError, match=r"structure\.bending_damping_ratio.*used only by the flexible structure"):
        plan(_spec(tmp_path, "bending_damping_ratio = [0.02, 0.03]"))
