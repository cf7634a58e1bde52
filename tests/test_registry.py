"""The registry of named building blocks."""

import pytest

from netsim.errors import ConfigError
from netsim.registry import lookup, register, resolve


@register("signal", "test_registry_shape", "a shape used only by this test")
class _Shape:
    pass


def test_registered_object_is_found_by_name():
    assert lookup("signal", "test_registry_shape") is _Shape


def test_unknown_name_suggests_the_closest_registered_one():
    with pytest.raises(ConfigError, match="did you mean 'test_registry_shape'"):
        lookup("signal", "test_registry_shap")


def test_module_path_resolves_without_registration():
    from netsim import timebase

    assert lookup("plant", "netsim.timebase:parse_time") is timebase.parse_time


def test_bad_module_path_is_a_config_error():
    with pytest.raises(ConfigError, match="cannot import module"):
        resolve("no_such_module_xyz:Thing")
    with pytest.raises(ConfigError, match="has no attribute"):
        resolve("netsim.timebase:no_such_thing")


def test_unknown_kind_is_rejected():
    with pytest.raises(ValueError, match="unknown registry kind"):
        register("gadget", "x")
