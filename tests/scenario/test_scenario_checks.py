"""Cross-reference, scheduling and naming-convention checks of scenarios, and their defaults."""

from __future__ import annotations

import sys
import textwrap

import pytest

from netsim import registry
from netsim.scenario import check_scenario, load_scenario
from netsim.distributions import Constant, Uniform
from netsim.scenario.schema import HandlerSpec, TaskSpec
from netsim.timebase import MS, US


def _problems(raw, severity="error"):
    return {p.path: p.message for p in check_scenario(raw) if p.severity == severity}


def test_times_are_integer_nanoseconds_and_defaults_are_filled(base):
    sc = load_scenario(base())
    sample = sc.nodes["sensor"].tasks[0]
    assert sample.period == 10 * MS and sample.deadline == 10 * MS and sample.offset == 0
    assert sample.release == "periodic" and sample.release_kind == "periodic" and sample.release_network is None
    ctl = sc.nodes["controller"].tasks[0]
    assert ctl.release_kind == "on_message" and ctl.release_network == "bus" and ctl.period is None
    assert isinstance(ctl.execution, Uniform) and (ctl.execution.low, ctl.execution.high) == (400 * US, 600 * US)
    assert sample.execution == 500 * US
    assert sc.duration == 1_000_000_000


def test_task_released_aperiodic_has_no_deadline(base):
    raw = base()  # without 'release: aperiodic' such a task is refused (issue 31: nothing would release it)
    raw["nodes"]["controller"]["tasks"].append({"name": "bg", "program": "zzt_idle", "release": "aperiodic"})
    task = load_scenario(raw).nodes["controller"].tasks[1]
    assert task.release == "aperiodic" and task.deadline is None


def test_execution_time_is_the_validated_distribution_itself(base):
    sc = load_scenario(base())
    assert sc.nodes["sensor"].tasks[0].execution_time() == Constant(value="500 us")  # a bare time: a constant
    controller = sc.nodes["controller"].tasks[0]
    assert controller.execution_time() is controller.execution  # no second parse of the YAML form
    assert (controller.execution.low, controller.execution.high) == (400 * US, 600 * US)
    assert sc.nodes["actuator"].handlers[0].execution_time() == Constant(value="20 us")


@pytest.mark.parametrize(
    ("spec", "path", "message"),
    [
        ({"dist": "unifrom", "low": 1}, "nodes.sensor.tasks[0].execution.dist",
         "unknown distribution 'unifrom'; did you mean 'uniform'?"),
        ({"low": "1 ms"}, "nodes.sensor.tasks[0].execution",
         "missing required key 'dist' (one of constant, uniform, normal, exponential, shifted_gamma, empirical)"),
        ({"dist": "uniform", "low": "2 ms", "high": "1 ms"}, "nodes.sensor.tasks[0].execution",
         "low must not exceed high"),
        ({"dist": "normal", "mean": "1 ms", "std": "0.1 ms", "bound": 1}, "nodes.sensor.tasks[0].execution.bound",
         "unknown key 'bound' (known keys: dist, max, mean, min, std)"),
        ([1, 2], "nodes.sensor.tasks[0].execution",
         "expected a time such as '0.5 ms' or {dist: uniform, low: .., high: ..}, got a list"),
    ],
)
def test_bad_execution_times(spec, path, message, base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["execution"] = spec
    assert _problems(raw) == {path: message}


def test_fixed_priority_tasks_need_a_priority(base):
    raw = base()
    del raw["nodes"]["sensor"]["tasks"][0]["priority"]
    assert _problems(raw) == {
        # the kernel's own check (FixedPriority.check), run by validate
        "nodes.sensor.tasks[0].priority": "is required under policy 'fp'; add e.g. 'priority: 1' "
        "(lower is more urgent) or use policy 'rm', 'dm' or 'edf'"
    }


def test_periodic_task_needs_a_period_and_others_have_none(base):
    raw = base()
    raw["nodes"]["controller"]["tasks"].append({"name": "p", "program": "zzt_idle", "release": "periodic"})
    raw["nodes"]["controller"]["tasks"][0]["period"] = "5 ms"
    assert _problems(raw) == {
        "nodes.controller.tasks[1].period": "a periodic task needs a period; add e.g. 'period: 10 ms', "
        "or set 'release: aperiodic' or 'release: on_message:<network>'",
        "nodes.controller.tasks[0].period": "only periodic tasks have a period (this one is released "
        "'on_message:bus'); remove 'period' or set 'release: periodic'",
    }


def test_deadline_longer_than_period_is_allowed_with_a_warning(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["deadline"] = "15 ms"
    assert _problems(raw) == {}
    assert _problems(raw, "warning") == {
        "nodes.sensor.tasks[0].deadline": "deadline 15 ms is longer than the period 10 ms; jobs may overlap (allowed)"
    }
    assert load_scenario(raw).nodes["sensor"].tasks[0].deadline == 15 * MS


def test_task_and_handler_names_are_unique_per_node(base):
    raw = base()
    raw["nodes"]["actuator"]["tasks"] = [{"name": "act", "program": "zzt_idle", "priority": 2, "period": "1 s"}]
    assert _problems(raw) == {
        "nodes.actuator.handlers[0].name": "duplicate name 'act' on node 'actuator': first defined at "
        "nodes.actuator.tasks[0]; task and handler names must be unique per node: rename one"
    }


def test_the_same_task_name_on_two_nodes_is_fine(base):
    raw = base()
    raw["nodes"]["controller"]["tasks"][0]["name"] = "sample"
    assert _problems(raw) == {}


def test_overrun_handlers_must_exist_on_the_node(base):
    raw = base()
    raw["nodes"]["actuator"]["tasks"] = [
        {"name": "t", "program": "zzt_idle", "priority": 2, "period": "1 s", "wcet": "1 ms", "wcet_handler": "act",
         "deadline_handler": "akt"}
    ]
    assert _problems(raw) == {
        "nodes.actuator.tasks[0].deadline_handler": "node 'actuator' has no handler 'akt'; did you mean 'act'?"
    }


def test_handler_trigger_takes_exactly_one_kind(base):
    raw = base()
    raw["nodes"]["actuator"]["handlers"][0]["trigger"] = {"on_message": "bus", "timer": {"period": "1 ms"}}
    assert _problems(raw) == {
        "nodes.actuator.handlers[0].trigger": "give exactly one of 'timer', 'on_message', 'external' or "
        "'periodic_load' (got timer, on_message)"
    }


def test_handler_trigger_kinds(base):
    raw = base()
    raw["nodes"]["actuator"]["handlers"].append(
        {"name": "tick", "program": "zzt_idle", "trigger": {"timer": {"period": "20 us"}}}
    )
    raw["nodes"]["actuator"]["handlers"].append(
        {"name": "ext", "program": "zzt_idle", "trigger": {"external": {"min_interarrival": "1 ms"}}}
    )
    handlers = load_scenario(raw).nodes["actuator"].handlers
    assert [h.trigger.kind for h in handlers] == ["on_message", "timer", "external"]
    assert handlers[1].trigger.timer.period == 20 * US and handlers[1].trigger.timer.start == 0
    assert handlers[2].trigger.external.min_interarrival == MS


def test_handler_on_message_needs_the_node_on_that_network(base):
    raw = base()
    raw["networks"]["bus"]["nodes"].remove("actuator")
    problems = _problems(raw)
    assert problems["nodes.actuator.handlers[0].trigger.on_message"] == (
        "node 'actuator' is not attached to network 'bus' (its nodes: sensor, controller); "
        "add 'actuator' to networks.bus.nodes"
    )


def test_unknown_policy_gets_a_suggestion(base):
    raw = base()
    raw["nodes"]["controller"]["policy"] = "edff"
    assert _problems(raw) == {"nodes.controller.policy": "unknown policy 'edff'; did you mean 'edf'?"}


@pytest.mark.parametrize(
    ("key", "value", "path", "message"),
    [
        ("channel", "yy", "nodes.sensor.tasks[0].params.channel", "unknown io channel 'yy'; did you mean 'y'?"),
        ("network", "bas", "nodes.sensor.tasks[0].params.network", "unknown network 'bas'; did you mean 'bus'?"),
    ],
)
def test_program_parameters_that_name_things_are_checked(key, value, path, message, base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["params"][key] = value
    assert _problems(raw) == {path: message}


def test_reference_and_suffix_conventions_are_checked(base):
    raw = base()
    raw["nodes"]["actuator"]["handlers"][0]["params"] = {"network": "bus", "reference": "rr", "out_channel": "v"}
    assert _problems(raw) == {
        "nodes.actuator.handlers[0].params.reference": "unknown signal 'rr'; did you mean 'r'?",
        "nodes.actuator.handlers[0].params.out_channel": "unknown io channel 'v' (known io channels: u, y)",
    }


def test_defaulted_program_parameters_are_checked_too(base):
    raw = base()
    del raw["io"]["u"]  # zzt_actuator's out_channel defaults to 'u'
    assert _problems(raw) == {
        "nodes.actuator.handlers[0].params.out_channel": "unknown io channel 'u' (known io channels: y)"
    }


def test_io_ports_must_exist_on_the_plant(base):
    raw = base()
    raw["io"]["y"]["output"] = 1
    raw["io"]["u"]["input"] = "w"
    assert _problems(raw) == {
        "io.y.output": "plant output index 1 out of range: the plant has 1 output (0..0)",
        "io.u.input": "the plant has no input 'w' (known inputs: d, u)",
    }


def test_io_channel_type_and_fields(base):
    raw = base()
    raw["io"]["enc"] = {"type": "encoder", "output": "y", "step": 5e-5, "tick": "10 us"}
    raw["io"]["y"]["saturation"] = [1, -1]
    raw["io"]["u"]["type"] = "dak"
    assert _problems(raw) == {
        "io.y.saturation": "expected [low, high] with low < high, got [1, -1]",
        "io.u.type": "unknown io channel type 'dak'; did you mean 'dac'?",
    }
    del raw["io"]["y"]["saturation"]
    raw["io"]["u"]["type"] = "dac"
    enc = load_scenario(raw).io["enc"]
    assert enc.tick == 10 * US and enc.mode == "exact" and enc.output == "y"


def test_io_without_a_plant_is_an_error(base):
    raw = base()
    del raw["plant"]
    assert _problems(raw) == {
        "io.y": "io channels connect to a plant, but the scenario has no 'plant:' section",
        "io.u": "io channels connect to a plant, but the scenario has no 'plant:' section",
    }


def test_disturbances_name_plant_inputs_and_signals(base):
    raw = base()
    raw["plant"]["disturbances"] = {"d": "r", "q": "load"}
    problems = [p for p in check_scenario(raw) if p.is_error]
    assert {p.path for p in problems} == {"plant.disturbances.q"}
    assert {p.message for p in problems} == {
        "the plant has no input 'q' (known inputs: d, u)",
        "unknown signal 'load' (known signals: r)",
    }


def test_record_names_must_be_text_and_are_not_guessed_statically(base):
    raw = base()
    raw["record"] = ["y", "y[0]", "ctl_state", "r", 3]  # r: the zzt_error metric reads it
    # 'ctl_state' may be recorded by a program: no warning before the run; a number is an error
    assert _problems(raw, "warning") == {}
    assert _problems(raw) == {"record[4]": "expected a signal name, got 3"}


def test_invalid_names_are_rejected(base):
    raw = base()
    raw["nodes"]["bad.name"] = {"policy": "edf"}
    raw["name"] = "my scenario"
    assert _problems(raw) == {
        "nodes.bad.name": "invalid name 'bad.name': use only letters, digits, '_' and '-'",
        "name": "invalid name 'my scenario': use only letters, digits, '_' and '-'",
    }


def test_validated_plugin_params_are_attached_with_defaults(base):
    sc = load_scenario(base())
    params = sc.nodes["sensor"].tasks[0].validated_params()
    assert isinstance(params, registry.lookup("program", "zzt_sampler").Params)
    assert (params.channel, params.bits, params.to) == ("y", 80, "controller")
    net = sc.networks["bus"].validated_params()
    assert net.bitrate == 80_000.0 and net.nodes == ["sensor", "controller", "actuator"]
    assert sc.signals["r"].validated_params().at == 100 * MS
    assert sc.nodes["controller"].tasks[0].validated_params() == {}  # zzt_idle has no Params
    assert sc.plant.validated_params().gain == 2.0


def test_validated_params_work_without_the_loader(base):
    from netsim.scenario.schema import Scenario

    sc = Scenario.model_validate(base())
    assert sc.plant.validated_params().pole == 1.0


def test_scenario_is_read_only(base):
    sc = load_scenario(base())
    with pytest.raises(Exception):
        sc.seed = 3  # type: ignore[misc]


def test_spec_lookups(base):
    sc = load_scenario(base())
    assert sc.node_networks("sensor") == ["bus"]
    assert sc.nodes["actuator"].handler("act").priority == 0
    assert isinstance(sc.nodes["sensor"].task("sample"), TaskSpec)
    assert isinstance(sc.nodes["actuator"].handlers[0], HandlerSpec)


def test_overrides_apply_before_validation(base):
    sc = load_scenario(base(), overrides={"nodes.sensor.tasks[0].period": "5 ms", "plant.x0": [1, 0]})
    assert sc.nodes["sensor"].tasks[0].period == 5 * MS and sc.plant.x0 == [1.0, 0.0]


def test_bad_override_is_a_problem(base):
    problems = check_scenario(base(), overrides={"nodes.sensr.tasks[0].period": "5 ms"})
    assert [(p.path, p.message) for p in problems] == [
        ("nodes.sensr.tasks[0].period", "cannot apply override: no key 'sensr' in 'nodes'; did you mean 'sensor'?")
    ]


def test_loading_never_modifies_the_input_dict(base):
    raw = base()
    load_scenario(raw, overrides={"seed": 4})
    assert raw == base()


def test_baseline_overrides_are_checked_and_applied(base):
    raw = base()
    raw["baseline"] = {"overrides": {"nodes.sensor.tasks[0].period": "1 ms"}}
    sc = load_scenario(raw)
    assert sc.baseline_scenario().nodes["sensor"].tasks[0].period == MS
    raw["baseline"] = {"overrides": {"nodes.sensor.tasks[0].period": "1 msec", "nodes.snsor.x": 1}}
    messages = sorted(p.message for p in check_scenario(raw) if p.is_error)
    assert messages == [
        "override 'nodes.snsor.x': no key 'snsor' in 'nodes'; did you mean 'sensor'?",
        "override gives nodes.sensor.tasks[0].period: unknown unit 'msec'; did you mean 'ms'?",
    ]


def test_a_broken_plugin_module_becomes_a_warning_not_a_crash(tmp_path, monkeypatch, base):
    # plugin modules load lazily (issue 19): the broken module declares the program the scenario names
    (tmp_path / "zzt_broken_plugins.py").write_text(
        "from netsim.registry import register\n\nraise RuntimeError('half written')\n\n"
        "@register('program', 'zzt_from_broken_module')\nclass P:\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("NETSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(registry, "PLUGIN_MODULES", [*registry.PLUGIN_MODULES, "zzt_broken_plugins"])
    monkeypatch.setattr(registry, "_PLUGINS_LOADED", False)
    monkeypatch.setattr(registry, "_PLUGIN_FAILURES", [])
    raw = base()
    raw["nodes"]["controller"]["tasks"][0]["program"] = "zzt_from_broken_module"
    problems = check_scenario(raw)
    warnings = [p.message for p in problems if not p.is_error]
    assert warnings == [
        "plugin module 'zzt_broken_plugins' failed to import (RuntimeError: half written); its plugins are unavailable"
    ]
    assert [p.path for p in problems if p.is_error] == ["nodes.controller.tasks[0].program"]
    sys.modules.pop("zzt_broken_plugins", None)


def test_plugin_files_register_programs_when_allowed(tmp_path, base):
    # issue 14: code comes from a file the scenario's plugins: names, and runs only when allowed
    plugin = tmp_path / "zzt_user_plugins.py"
    plugin.write_text(
        textwrap.dedent(
            """
            from netsim.registry import register
            from netsim.units import StrictModel

            @register("program", "zzt_user_program")
            class MyProgram:
                class Params(StrictModel):
                    gain: float

                def __init__(self, ctx, params):  # build calls cls(ctx, params); validate checks that it can
                    self.params = params
            """
        )
    )
    raw = base()
    raw["plugins"] = [str(plugin)]
    raw["nodes"]["controller"]["tasks"][0].update(program="zzt_user_program", params={"gain": 2})
    try:
        assert load_scenario(raw, allow_plugins=True).nodes["controller"].tasks[0].validated_params().gain == 2.0
        raw["nodes"]["controller"]["tasks"][0]["program"] = "zzt_user_progam"
        assert _problems(raw) == {
            "nodes.controller.tasks[0].program": "unknown program 'zzt_user_progam'; did you mean 'zzt_user_program'?"
        }
    finally:  # the program must not outlive this test (test_docs_and_schema lists every registered program)
        from netsim import registry

        registry._REGISTRY["program"].pop("zzt_user_program", None)
        module = registry._PLUGIN_FILES.pop(str(plugin.resolve()), None)
        if module:
            sys.modules.pop(module, None)


def test_a_node_has_one_receiver_per_network(base):
    raw = base()
    raw["nodes"]["actuator"]["tasks"] = [{"name": "also", "program": "zzt_idle", "release": "on_message:bus",
                                         "priority": 1}]
    assert _problems(raw) == {
        "nodes.actuator.handlers[0].trigger.on_message": "messages from network 'bus' already go to "
        "nodes.actuator.tasks[0] on node 'actuator'; a node has one receiver per network (let that program hand "
        "messages on)"
    }


def test_overriding_a_loaded_scenario_keeps_derived_defaults_derived(base):
    sc = load_scenario(base())
    again = load_scenario(sc, overrides={"nodes.sensor.tasks[0].period": "4 ms"})
    assert again.nodes["sensor"].tasks[0].deadline == 4 * MS  # the default deadline follows the period
    assert load_scenario(sc) is sc


def test_trigger_is_written_with_only_its_kind(base):
    data = load_scenario(base()).resolved_dict()
    assert data["nodes"]["actuator"]["handlers"][0]["trigger"] == {"on_message": "bus"}


def test_offset_on_an_aperiodic_task_is_an_error(base):
    raw = base()
    node = next(iter(raw["nodes"].values()))
    node.setdefault("tasks", []).append({"name": "late", "program": node["tasks"][0]["program"],
                                         "params": node["tasks"][0].get("params", {}), "priority": 3,
                                         "release": "aperiodic", "offset": "1 ms"})
    index = len(node["tasks"]) - 1
    node_name = next(iter(raw["nodes"]))
    assert _problems(raw) == {
        # the kernel's own check (netsim.kernel.building.task_spec), run by validate
        f"nodes.{node_name}.tasks[{index}].offset": "applies to periodic and sporadic tasks only; give a period or drop it"
    }


def test_metric_signal_left_out_of_record_is_an_error_naming_the_metric(base):
    raw = base()
    raw["record"] = ["y", "u"]  # the zzt_error metric reads 'r'
    assert _problems(raw) == {
        "metrics[0].params.reference": "metric 'zzt_error' reads signal 'r', which 'record:' leaves out "
        "(record: [y, u]); add 'r' to 'record:'"
    }


def test_metric_signals_are_not_checked_when_everything_is_recorded(base):
    raw = base()
    del raw["record"]
    raw["metrics"][0]["params"]["reference"] = "anything"  # omitted record: every signal is recorded
    assert _problems(raw) == {}


def test_metric_signal_conventions_cover_output_signal_and_suffixed_fields(base):
    from netsim.registry import register
    from netsim.units import StrictModel

    @register("metric", "zzt_multi", "test metric reading several signals")
    def zzt_multi(result, params, baseline=None):
        return {}

    class Params(StrictModel):
        output: str = "y"            # a default counts too: the metric reads it
        signal: str | None = None
        error_signal: str
        signals: list[str] = []

    zzt_multi.Params = Params
    raw = base()
    raw["record"] = ["y", "u", "r", "x[0]"]
    raw["metrics"].append({"type": "zzt_multi", "params": {"error_signal": "e", "signal": "x[0]",
                                                           "signals": ["u", "v"]}})
    assert set(_problems(raw)) == {"metrics[1].params.error_signal", "metrics[1].params.signals[1]"}
    raw["metrics"][1]["params"]["signal"] = "z[1]"   # an element of a vector needs the vector or itself
    raw["record"] = ["y", "u", "r", "z", "e", "v"]
    assert _problems(raw) == {}


def test_latency_chain_entries_must_name_existing_tasks_or_handlers(base):
    raw = base()
    raw["metrics"].append({"type": "latency", "params": {
        "chain": ["sensor.sample", "controller.ctl", "actuator.act",      # a task, a task, a handler: fine
                  "sensor.nope", "sensr.sample", "controller.cl", "oops"]}})
    assert _problems(raw) == {
        "metrics[1].params.chain[3]": "node 'sensor' has no task or handler 'nope' (known tasks and handlers: sample)",
        "metrics[1].params.chain[4]": "unknown node 'sensr'; did you mean 'sensor'?",
        "metrics[1].params.chain[5]": "node 'controller' has no task or handler 'cl'; did you mean 'ctl'?",
        "metrics[1].params.chain[6]": "expected 'node.task', got 'oops'",
    }
