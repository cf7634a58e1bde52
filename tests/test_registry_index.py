"""Lazy plugin loading (issue 19): the index of ``@register`` lines read from the sources, and its cache.

The index must equal what importing every plugin module registers (a new ``@register`` line can never be
missed), a lookup must import only the module that declares the name, and ``netsim validate`` of a simple
scenario must import neither pandas nor python-control.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from netsim import registry
from netsim.errors import ConfigError
from netsim.registry.index import declarations_in, plugin_index

ROOT = Path(__file__).resolve().parents[1]


def _python(code: str, cache: Path) -> dict:
    env = {**os.environ, "NETSIM_CACHE_DIR": str(cache), "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, cwd=ROOT,
                         env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


_LAZY_VS_FULL = """
    import json, sys
    from netsim import registry

    index = registry._index()
    lazy = {}
    for d in index.declarations:
        lazy[f"{d.kind}/{d.name}"] = registry._origin(registry.lookup(d.kind, d.name))
    imported_by_lazy = sorted(m for m in sys.modules if m.startswith(("netsim.", "models.")))
    failures = registry.load_plugins()
    full = {f"{k}/{e.name}": registry._origin(e.obj) for k in registry.kinds() for e in registry._REGISTRY[k].values()}
    print(json.dumps({"lazy": lazy, "full": full, "opaque": index.opaque, "failures": failures,
                      "declared_in": {f"{d.kind}/{d.name}": d.module for d in index.declarations}}))
"""


@pytest.fixture(scope="module")
def lazy_vs_full(tmp_path_factory):
    """In a fresh process with an empty cache: every declared name looked up lazily, then everything imported."""
    return _python(_LAZY_VS_FULL, tmp_path_factory.mktemp("cache"))


def test_the_index_declares_exactly_what_importing_every_plugin_module_registers(lazy_vs_full):
    assert lazy_vs_full["failures"] == []
    assert lazy_vs_full["opaque"] == []  # every register() call of netsim and models is read from its source
    assert sorted(lazy_vs_full["lazy"]) == sorted(lazy_vs_full["full"])
    assert len(lazy_vs_full["full"]) >= 60  # networks, policies, signals, programs, metrics, plants, reports
    # a lazy lookup finds the very object the full import registers (same module and qualname)
    assert lazy_vs_full["lazy"] == lazy_vs_full["full"]


def test_each_declaration_names_the_module_whose_import_registers_it(lazy_vs_full):
    # the object may be defined elsewhere (an alias), but the declaring module is the one under a plugin package
    assert all(registry.is_plugin_module(m) for m in lazy_vs_full["declared_in"].values())
    assert lazy_vs_full["declared_in"]["network/can"] == "netsim.network.can"
    assert lazy_vs_full["declared_in"]["plant/dc_servo"] == "netsim.models.dc_servo"


def test_a_lookup_imports_only_the_module_that_declares_the_name(tmp_path):
    code = """
        import json, sys
        from netsim import registry
        registry.lookup("plant", "dc_servo")
        print(json.dumps(sorted(m for m in sys.modules if m.startswith("netsim.models"))))
    """
    assert _python(code, tmp_path) == ["netsim.models", "netsim.models.dc_servo"]


def test_netsim_validate_of_a_simple_scenario_imports_no_pandas_or_python_control(tmp_path):
    code = """
        import io, json, sys, contextlib
        from netsim.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            rc = main(["validate", "scenarios/dc_servo_can.yaml"])
        heavy = ("pandas", "control", "matplotlib", "dask", "scipy.signal", "scipy.sparse", "scipy.integrate")
        print(json.dumps({"rc": rc, "heavy": sorted(m for m in heavy if m in sys.modules),
                          "models": sorted(m for m in sys.modules if m.startswith("netsim.models"))}))
    """
    out = _python(code, tmp_path)
    assert out == {"rc": 0, "heavy": [], "models": ["netsim.models", "netsim.models.dc_servo"]}


def test_the_cache_is_written_and_a_changed_file_is_read_again(tmp_path, monkeypatch):
    pkg = tmp_path / "src" / "zzt_idx_pkg"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    mod = pkg / "zzt_mod.py"
    mod.write_text("from netsim.registry import register\n\n@register('metric', 'zzt_idx_one')\ndef one(r, p, b):\n"
                   "    return {}\n")
    monkeypatch.syspath_prepend(str(tmp_path / "src"))
    monkeypatch.setenv("NETSIM_CACHE_DIR", str(tmp_path / "cache"))
    kinds = registry.KINDS
    first = plugin_index(["zzt_idx_pkg"], kinds, refresh=True)
    assert [(d.kind, d.name, d.module, d.line) for d in first.declarations] == [
        ("metric", "zzt_idx_one", "zzt_idx_pkg.zzt_mod", 3)]
    cache = json.loads(next((tmp_path / "cache").glob("plugin-index-*.json")).read_text())
    assert cache["files"][str(mod.resolve())]["decl"] == [["metric", "zzt_idx_one", 3]]
    # a record in the cache is trusted while the file's mtime and size match: a forged one shows it is used
    cache["files"][str(mod.resolve())]["decl"] = [["metric", "zzt_idx_from_cache", 3]]
    next((tmp_path / "cache").glob("plugin-index-*.json")).write_text(json.dumps(cache))
    assert [d.name for d in plugin_index(["zzt_idx_pkg"], kinds, refresh=True).declarations] == ["zzt_idx_from_cache"]
    # the file changes (size and mtime): parsed again
    mod.write_text(mod.read_text() + "\n@register('metric', 'zzt_idx_two')\ndef two(r, p, b):\n    return {}\n")
    os.utime(mod, ns=(mod.stat().st_atime_ns, mod.stat().st_mtime_ns + 10**9))
    again = plugin_index(["zzt_idx_pkg"], kinds, refresh=True)
    assert [d.name for d in again.declarations] == ["zzt_idx_one", "zzt_idx_two"]


def test_an_unwritable_cache_leaves_the_index_correct(tmp_path, monkeypatch):
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("a file where the cache folder should be")
    monkeypatch.setenv("NETSIM_CACHE_DIR", str(blocker / "netsim"))
    index = plugin_index(["netsim.network"], registry.KINDS, refresh=True)
    assert "netsim.network.can" in index.modules_for("network", "can")


def test_a_module_written_after_the_first_lookup_is_found(tmp_path, monkeypatch):
    pkg = tmp_path / "zzt_late_pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("NETSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(registry, "PLUGIN_MODULES", [*registry.PLUGIN_MODULES, "zzt_late_pkg"])
    monkeypatch.setattr(registry, "_PLUGINS_LOADED", False)
    monkeypatch.setitem(registry._REGISTRY, "signal", dict(registry._REGISTRY["signal"]))
    with pytest.raises(ConfigError, match="unknown signal 'zzt_late_shape'"):
        registry.lookup("signal", "zzt_late_shape")
    (pkg / "late.py").write_text("from netsim.registry import register\n\n@register('signal', 'zzt_late_shape')\n"
                                 "class Late:\n    pass\n")
    assert registry.lookup("signal", "zzt_late_shape").__module__ == "zzt_late_pkg.late"
    for name in [m for m in sys.modules if m.startswith("zzt_late_pkg")]:
        monkeypatch.delitem(sys.modules, name)


def test_a_name_whose_module_fails_to_import_says_why(tmp_path, monkeypatch):
    (tmp_path / "zzt_idx_broken.py").write_text(
        "from netsim.registry import register\n\nraise RuntimeError('half written')\n\n"
        "@register('program', 'zzt_idx_half')\nclass Half:\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("NETSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(registry, "PLUGIN_MODULES", [*registry.PLUGIN_MODULES, "zzt_idx_broken"])
    monkeypatch.setattr(registry, "_PLUGINS_LOADED", False)
    monkeypatch.setattr(registry, "_PLUGIN_FAILURES", [])
    monkeypatch.setitem(registry._REGISTRY, "program", dict(registry._REGISTRY["program"]))
    with pytest.raises(ConfigError, match=r"program 'zzt_idx_half' is unavailable: its module 'zzt_idx_broken' "
                                          r"failed to import \(RuntimeError: half written\); fix that module"):
        registry.lookup("program", "zzt_idx_half")
    assert registry.plugin_failures() == [("zzt_idx_broken", "RuntimeError: half written")]
    sys.modules.pop("zzt_idx_broken", None)


def test_declarations_are_string_literals_and_anything_else_makes_the_module_opaque():
    kinds = registry.KINDS
    src = textwrap.dedent("""
        import atexit
        from netsim.registry import register
        atexit.register(print)                       # not a plugin declaration: one argument
        @register("metric", "m1", "a summary")
        def m1(r, p, b): ...
        @registry.register("network", "n1")
        class N1: ...
        x = '@register("plant", "in_a_string")'     # text, not code
    """)
    assert declarations_in(src, kinds) == ([("metric", "m1", 5), ("network", "n1", 7)], False)
    assert declarations_in('register("plant", NAME)(f)\n', kinds)[1] is True
    assert declarations_in('register(KIND, "x")(f)\n', kinds)[1] is True
    assert declarations_in('register(kind="plant", name="x")(f)\n', kinds)[1] is True
    with pytest.raises(SyntaxError):
        declarations_in("def broken(:\n", kinds)


def test_the_index_walks_the_same_modules_as_load_plugins_in_the_same_order():
    # load_plugins imports with pkgutil.iter_modules; the index lists directories itself (no import, no pkgutil)
    import importlib
    import pkgutil

    from netsim.registry.index import _walk

    def walk(name: str, out: list[str]) -> None:
        out.append(name)
        module = importlib.import_module(name)
        for info in sorted(pkgutil.iter_modules(getattr(module, "__path__", None) or []), key=lambda i: i.name):
            if info.name != "__main__":
                walk(f"{name}.{info.name}", out)

    expected: list[str] = []
    for root in registry.PLUGIN_MODULES:
        walk(root, expected)
    assert [m for root in registry.PLUGIN_MODULES for m, _ in _walk(root)] == expected
    assert len(expected) > 100  # netsim's plugin packages and the case studies


def test_two_threads_looking_up_a_name_whose_module_is_still_importing_both_find_it(tmp_path, monkeypatch):
    # a threaded sweep: the second lookup must wait for the first one's import, not report an unknown name
    import threading

    (tmp_path / "zzt_idx_slow.py").write_text(
        "import time\nfrom netsim.registry import register\n\ntime.sleep(0.3)\n\n"
        "@register('metric', 'zzt_idx_slow')\ndef slow(r, p, b):\n    return {}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("NETSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(registry, "PLUGIN_MODULES", [*registry.PLUGIN_MODULES, "zzt_idx_slow"])
    monkeypatch.setattr(registry, "_PLUGINS_LOADED", False)
    monkeypatch.setitem(registry._REGISTRY, "metric", dict(registry._REGISTRY["metric"]))
    registry._index(refresh=True)  # both threads then go straight to the import
    found: list[object] = []

    def look() -> None:
        try:
            found.append(registry.lookup("metric", "zzt_idx_slow").__name__)
        except ConfigError as exc:
            found.append(str(exc))

    threads = [threading.Thread(target=look) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert found == ["slow", "slow"]
    sys.modules.pop("zzt_idx_slow", None)
