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


def test_module_path_names_a_registered_object():
    assert lookup("signal", f"{__name__}:_Shape") is _Shape


def test_module_path_to_an_unregistered_function_is_refused():
    # issue 14: a path is another spelling of a registered plugin, never an arbitrary callable
    with pytest.raises(ConfigError, match="is not a registered plant or a subclass of netsim.plant.Plant"):
        lookup("plant", "netsim.timebase:parse_time")


def test_bad_module_path_is_a_config_error():
    with pytest.raises(ConfigError, match="which netsim does not import for a scenario"):
        resolve("no_such_module_xyz:Thing", "plant")
    with pytest.raises(ConfigError, match="cannot import module"):
        resolve("netsim.no_such_module_xyz:Thing", "plant")
    with pytest.raises(ConfigError, match="has no attribute"):
        resolve("netsim.timebase:no_such_thing", "plant")


def test_unknown_kind_is_rejected():
    with pytest.raises(ValueError, match="unknown registry kind"):
        register("gadget", "x")
