"""Policy names are resolved in one place, :func:`netsim.kernel.policies.find_policy`."""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError, ConfigError
from netsim.kernel import Kernel
from netsim.kernel.policies import (BUILTIN_POLICIES, EarliestDeadlineFirst, NonPreemptiveEDF, Policy,
                                    find_policy, is_builtin_policy, resolve_policy)


def test_builtin_names_resolve_to_their_classes_without_an_instance():
    for name, cls in BUILTIN_POLICIES.items():
        assert find_policy(name) is cls
        assert is_builtin_policy(name)
        assert cls.name == name
    assert set(BUILTIN_POLICIES) == {"fp", "rm", "dm", "edf", "np_fp", "np_edf", "tt"}
    assert not is_builtin_policy("netsim.kernel.policies:FixedPriority")
    assert not is_builtin_policy(None)


def test_a_module_path_resolves_through_the_registry_and_the_kernel_instantiates_it():
    assert find_policy("netsim.kernel.policies:NonPreemptiveEDF") is NonPreemptiveEDF
    k = Kernel(SimEnv(), "n", policy="netsim.kernel.policies:NonPreemptiveEDF")
    assert isinstance(k.policy, NonPreemptiveEDF) and not k.policy.preemptive


def test_an_unknown_name_is_a_config_error_with_a_suggestion_and_the_kernel_names_its_node():
    with pytest.raises(ConfigError, match=r"^unknown policy 'edff'; did you mean 'edf'\?$"):
        find_policy("edff")
    with pytest.raises(BuildError, match=r"^node 'cpu': unknown policy 'np_edff'; did you mean 'np_edf'\?$"):
        Kernel(SimEnv(), "cpu", policy="np_edff")


def test_something_that_is_not_a_policy_is_refused_with_its_name():
    with pytest.raises(ConfigError, match=r"Policy"):
        find_policy("netsim.kernel.states:STATE_NAMES")
    with pytest.raises(BuildError, match=r"node 'cpu': scheduling policy: .*Policy"):
        Kernel(SimEnv(), "cpu", policy="netsim.kernel.states:STATE_NAMES")
    with pytest.raises(BuildError, match=r"node 'cpu': policy must be a name"):
        Kernel(SimEnv(), "cpu", policy=3)  # type: ignore[arg-type]


def test_instances_and_classes_are_used_as_given():
    edf = EarliestDeadlineFirst()
    assert resolve_policy(edf, "n") is edf
    assert type(resolve_policy(EarliestDeadlineFirst, "n")) is EarliestDeadlineFirst
    assert isinstance(resolve_policy("dm", "n"), Policy)
