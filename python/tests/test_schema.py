"""curvefem.schema(): the case keys as data, against what read_case accepts and resolves."""

import pytest

import curvefem

CUBE = {"geometry": {"builtin": {"shape": "cube", "divisions": 1}}}


def top_level_sections():
    return list(dict.fromkeys(k["path"].split(".")[0].removesuffix("[]")
                              for k in curvefem.schema()))


def test_schema_lists_every_key_once_with_its_fields():
    keys = curvefem.schema()
    paths = [k["path"] for k in keys]
    assert len(paths) == len(set(paths))
    for k in keys:
        assert set(k) >= {"path", "type", "default", "default_text", "allowed", "minimum",
                          "maximum", "type_text", "doc"}
        assert k["doc"], k["path"]
    meshing = {k["path"]: k for k in curvefem.schema("meshing")}
    assert all(p.startswith("meshing.") for p in meshing)
    assert meshing["meshing.eps"]["maximum"] == 0.5 and meshing["meshing.eps"]["minimum_exclusive"]
    assert "given" in meshing["meshing.method"]["allowed"]


def test_every_documented_top_level_section_is_accepted():
    sections = top_level_sections()
    assert {"geometry", "meshing", "physics", "solver", "boundary_conditions"} <= set(sections)
    for section in sections:
        case = dict(CUBE)
        case.setdefault(section, "?")
        try:
            curvefem.read_case(case)
        except curvefem.InputError as e:  # a bad value, but not an unknown key
            assert "/%s: unknown key" % section not in str(e), str(e)
    with pytest.raises(curvefem.InputError) as info:
        curvefem.read_case(dict(CUBE, not_a_section={}))
    assert "/not_a_section: unknown key" in str(info.value)
    # The parser's list of allowed keys is the schema's.
    assert "(allowed here: %s)" % ", ".join(sorted(sections)) in str(info.value)


def test_schema_defaults_are_what_a_minimal_case_resolves_to():
    resolved = curvefem.resolved(CUBE)
    compared = 0
    for k in curvefem.schema():
        section, _, key = k["path"].partition(".")
        if k["default"] is None or section not in ("physics", "discretization", "solver"):
            continue
        if key in resolved.get(section, {}):
            assert resolved[section][key] == k["default"], k["path"]
            compared += 1
    assert compared >= 8


def test_case_docstring_lists_the_sections():
    for section in top_level_sections():
        assert "        %s=" % section in curvefem.case.__doc__


def test_case_keyword_arguments_are_checked_against_the_schema_at_every_depth():
    ok = curvefem.case(
        geometry={"builtin": {"shape": "cube", "divisions": 1}},
        meshing={"method": "given"},
        physics={"type": "poisson"},
        boundary_conditions=[{"type": "dirichlet", "select": {"and": [
            {"box": [[0, 0, 0], [1, 1, 1]]}, {"not": {"plane": {"point": [0, 0, 0],
                                                                "normal": [1, 0, 0]}}}]},
            "value": "x"}],
        load_cases=[{"name": "a", "rhs": "1", "boundary_conditions": [
            {"type": "dirichlet", "select": {"all": True}, "value": "0"}]}],
        solver={"type": "direct"})
    assert ok["meshing"] == {"method": "given"}
    bad = [
        (dict(meshng={}), "meshng", "meshing"),
        (dict(meshing={"epss": 0.01}), "meshing.epss", "eps"),
        (dict(solver={"preconditoner": "gamg"}), "solver.preconditoner", "preconditioner"),
        (dict(boundary_conditions=[{"type": "dirichlet", "select": {"boxx": []}}]),
         "boundary_conditions[0].select.boxx", "box"),
        (dict(boundary_conditions=[{"type": "neumann", "select": {"or": [
            {"all": True}, {"plane": {"point": [0, 0, 0], "normall": [1, 0, 0]}}]}}]),
         "boundary_conditions[0].select.or[1].plane.normall", "normal"),
        (dict(load_cases=[{"name": "a", "boundary_conditions": [{"tpye": "dirichlet"}]}]),
         "load_cases[0].boundary_conditions[0].tpye", "type"),
    ]
    for kwargs, where, suggestion in bad:
        with pytest.raises(curvefem.InputError) as info:
            curvefem.case(**kwargs)
        assert where in str(info.value), str(info.value)
        assert "did you mean %r" % suggestion in str(info.value), str(info.value)


def test_the_rules_between_keys_are_data_and_the_reader_follows_them():
    keys = {k["path"]: k for k in curvefem.schema()}
    assert keys["meshing.order"]["when"] == [
        {"path": "geometry.mesh_dir", "given": False},
        {"path": "meshing.method", "values": ["curved"]}]
    assert keys["physics.kappa_inside"]["default_from"] == "physics.kappa"
    # A curved key on a given mesh: refused, naming the key and the rule.
    with pytest.raises(curvefem.InputError) as info:
        curvefem.read_case(dict(CUBE, meshing={"order": 2}))
    assert '/meshing/order: only for method "curved"' in str(info.value)
    # Where every rule holds the key is read; where one fails resolved() leaves it out.
    sphere = {"geometry": {"builtin_surface": {"shape": "sphere"}}}
    assert curvefem.resolved(sphere)["meshing"]["order"] == keys["meshing.order"]["default"]
    assert "order" not in curvefem.resolved(CUBE)["meshing"]
    both = dict(sphere, meshing={"exterior": True, "solve_on": "both"},
                physics={"kappa": "3"})
    assert curvefem.resolved(both)["physics"]["kappa_inside"] == "3"
    # A default that depends on another key: the first entry whose rules hold.
    elastic = dict(CUBE, physics={"type": "linear_elasticity"})
    assert curvefem.resolved(elastic)["discretization"]["partial_dirichlet"] == "nodal"
    assert curvefem.resolved(CUBE)["discretization"]["partial_dirichlet"] == "nitsche"
