"""Configuration: Table 4.1 defaults, validation in one place, YAML and overrides."""

from __future__ import annotations

import dataclasses

import pytest

from ontodetect.config import (
    ClusterConfig,
    Config,
    ConfigValueError,
    PlaneConfig,
    PrepareConfig,
    UnknownKeyError,
    parse_override,
)
from ontodetect.errors import InvalidParameterError, OntoDetectError, ReadError


def test_defaults_follow_table_4_1():
    cfg = Config()
    assert cfg.prepare.voxel_size == 0.02  # voxel size 2 cm
    assert cfg.prepare.altitude_cutoff == 1.4  # altitude cut-off 140 cm
    assert cfg.cluster.radius == 0.05  # DBSCAN radius 2-5 cm
    assert cfg.cluster.length == (0.3, 2.0)  # cluster length 30-200 cm
    assert cfg.cluster.min_planes == 2  # at least 2 planes
    assert cfg.planes.threshold == 0.01  # inlier distance 1 cm (0.5-1.5)
    assert cfg.planes.min_extent == 0.25  # plane size from 25 cm
    assert cfg.cluster.part_height[0] <= 0.35 and cfg.cluster.part_height[1] >= 0.75


def test_sections_are_frozen():
    cfg = Config()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.cluster.radius = 0.1  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.cluster = ClusterConfig()  # type: ignore[misc]


@pytest.mark.parametrize(
    ("key", "value", "match"),
    [
        (
            "cluster.radius",
            -1,
            r"The 'cluster\.radius' parameter must be a float in the range "
            r"\(0, inf\)\. Got -1 instead\.",
        ),
        ("cluster.radius", 0, r"'cluster\.radius'.*\(0, inf\).*Got 0 instead"),
        ("cluster.radius", "wide", r"'cluster\.radius'.*Got 'wide' instead"),
        ("cluster.radius", True, r"'cluster\.radius'.*Got True instead"),
        ("cluster.radius", float("nan"), r"'cluster\.radius'"),
        ("cluster.min_planes", 2.5, r"'cluster\.min_planes' parameter must be an int"),
        ("cluster.min_planes", -1, r"'cluster\.min_planes'.*\[0, 1000\]"),
        ("cluster.method", "kmeans", r"'cluster\.method'.*one of 'parts', 'dbscan'"),
        ("cluster.length", [2.0, 0.3], r"'cluster\.length'.*low <= high.*Got \[2\.0, 0\.3\]"),
        ("cluster.length", [0.3], r"'cluster\.length'.*pair"),
        ("cluster.core_fill", 1.5, r"'cluster\.core_fill'.*\[0, 1\]"),
        ("prepare.voxel_size", -0.02, r"'prepare\.voxel_size'"),
        ("prepare.up", "w", r"'prepare\.up'.*one of 'z', '-z'"),
        ("prepare.scale", 0, r"'prepare\.scale'.*null or a float"),
        ("prepare.denoise", "median", r"'prepare\.denoise'"),
        ("prepare.far_percentile", 50, r"'prepare\.far_percentile'.*\[0, 50\)"),
        ("planes.threshold", 0, r"'planes\.threshold'"),
        ("planes.max_trials", 0, r"'planes\.max_trials'"),
    ],
)
def test_bad_values_name_the_parameter(key, value, match):
    section, name = key.split(".")
    with pytest.raises(InvalidParameterError, match=match):
        Config.from_dict({section: {name: value}})
    with pytest.raises(InvalidParameterError, match=match):
        Config().replace(**{section: {name: value}})


def test_integers_become_floats_and_lists_pairs():
    cfg = Config.from_dict({"cluster": {"radius": 1, "length": [1, 3]}})
    assert cfg.cluster.radius == 1.0 and isinstance(cfg.cluster.radius, float)
    assert cfg.cluster.length == (1.0, 3.0)
    assert Config.from_dict({"planes": {"max_planes": 4.0}}).planes.max_planes == 4


def test_unknown_keys_name_key_and_file(tmp_path):
    path = tmp_path / "cfg.yaml"
    path.write_text("cluster:\n  radiuss: 0.04\n")
    with pytest.raises(
        UnknownKeyError,
        match=r"cfg\.yaml: unknown configuration key "
        r"'cluster\.radiuss'.*cluster\.radius",
    ):
        Config.from_yaml(path)
    path.write_text("clustering:\n  radius: 0.04\n")
    with pytest.raises(UnknownKeyError, match=r"cfg\.yaml.*'clustering'"):
        Config.from_yaml(path)


def test_bad_value_in_file_names_the_file(tmp_path):
    path = tmp_path / "cfg.yaml"
    path.write_text("cluster:\n  radius: -1\n")
    with pytest.raises(ConfigValueError, match=r"cfg\.yaml: The 'cluster\.radius' parameter"):
        Config.from_yaml(path)


def test_file_problems_are_read_errors(tmp_path):
    with pytest.raises(ReadError, match="no such configuration file"):
        Config.from_yaml(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("cluster: [radius\n")
    with pytest.raises(ReadError, match=r"bad\.yaml: invalid YAML \(line"):
        Config.from_yaml(bad)
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text("- 1\n- 2\n")
    with pytest.raises(InvalidParameterError, match="mapping of sections"):
        Config.from_yaml(wrong)
    fmt = tmp_path / "fmt.yaml"
    fmt.write_text("format: something/2\n")
    with pytest.raises(InvalidParameterError, match="format"):
        Config.from_yaml(fmt)


def test_yaml_round_trip(tmp_path):
    cfg = Config().with_overrides(
        [
            "cluster.radius=0.03",
            "prepare.up=auto",
            "prepare.scale=0.001",
            "cluster.length=[0.2, 2.5]",
        ]
    )
    path = tmp_path / "c.yaml"
    text = cfg.to_yaml(path)
    assert path.read_text() == text
    assert "length: [0.2, 2.5]" in text
    back = Config.from_yaml(path)
    assert back == cfg
    assert Config.from_dict(cfg.to_dict()) == cfg
    # An empty file or empty section is the defaults.
    empty = tmp_path / "e.yaml"
    empty.write_text("")
    assert Config.from_yaml(empty) == Config()
    assert Config.from_dict({"cluster": None}) == Config()


def test_partial_yaml_keeps_other_defaults():
    cfg = Config.from_yaml_text("planes:\n  threshold: 0.015\n")
    assert cfg.planes.threshold == 0.015
    assert cfg.planes.max_trials == PlaneConfig().max_trials
    assert cfg.prepare == PrepareConfig()


@pytest.mark.parametrize(
    ("text", "key", "value"),
    [
        ("cluster.radius=0.04", "cluster.radius", 0.04),
        ("cluster.method=dbscan", "cluster.method", "dbscan"),
        ("prepare.scale=null", "prepare.scale", None),
        ("prepare.scale=", "prepare.scale", None),
        ("cluster.length=[0.2, 3]", "cluster.length", [0.2, 3]),
        ("prepare.smoothing=true", "prepare.smoothing", True),
        (" cluster.radius = 0.04 ", "cluster.radius", 0.04),
    ],
)
def test_parse_override(text, key, value):
    assert parse_override(text) == (key, value)


def test_overrides_apply_and_validate():
    cfg = Config().with_overrides(["cluster.radius=0.04", "cluster.method=dbscan"])
    assert cfg.cluster.radius == 0.04 and cfg.cluster.method == "dbscan"
    assert cfg.get("cluster.radius") == 0.04
    assert Config().cluster.radius == 0.05  # the original is unchanged
    with pytest.raises(InvalidParameterError, match=r"'--set'.*section\.key=value"):
        Config().with_overrides(["cluster.radius"])
    with pytest.raises(UnknownKeyError, match=r"'cluster\.nope'"):
        Config().with_overrides(["cluster.nope=1"])
    with pytest.raises(UnknownKeyError, match=r"'radius'"):
        Config().with_overrides(["radius=1"])
    with pytest.raises(OntoDetectError, match=r"'cluster\.radius'.*Got -0\.5"):
        Config().with_overrides(["cluster.radius=-0.5"])


def test_describe_lists_every_field():
    names = [row[0] for row in ClusterConfig.describe()]
    assert names == [f.name for f in dataclasses.fields(ClusterConfig)]
    assert all(row[3] for row in ClusterConfig.describe())  # every field documented


def test_config_rejects_wrong_section_types():
    with pytest.raises(InvalidParameterError, match="ClusterConfig"):
        Config(cluster=PrepareConfig())  # type: ignore[arg-type]
