"""User-facing exceptions survive being re-created from their args (simpy re-raises failed events that way)."""

import pytest

from netsim.errors import BuildError, ConfigError, DivergenceError, LivelockError


@pytest.mark.parametrize(
    "exc",
    [
        ConfigError("unknown unit 'usec'", "nodes.a.tasks[0].period"),
        ConfigError("plain message"),
        BuildError("body is not a generator", "nodes.a.tasks[1]"),
        DivergenceError("plant diverged at t = 1.2 s", 1_200_000_000),
        LivelockError("zero-time loop", ["isr", "task"]),
    ],
)
def test_exception_recreated_from_args_keeps_message_and_fields(exc):
    copy = type(exc)(*exc.args)
    assert str(copy) == str(exc)
    assert vars(copy) == vars(exc)


def test_config_error_message_names_the_path():
    assert str(ConfigError("must be positive", "networks.can.bitrate")) == "networks.can.bitrate: must be positive"
