"""Whether the user allows scenarios to load code from the plugin files they name (issue 14).

A scenario's ``plugins:`` list names Python files that register plugins. netsim runs such a file only when the
user said so, in one of these ways (the first that gives an answer wins):

1. the caller's own choice: ``--allow-plugins`` on the command line (``run``, ``validate``, ``batch``,
   ``sweep``), ``allow_plugins=True`` in :func:`netsim.run` / :func:`netsim.load_scenario`
   (``allow_plugins=False`` refuses even when the settings below allow);
2. in a worker process the sweep did not start (a Dask worker of a remote scheduler, issue 31), the choice of the
   user who submitted the task, which travels with it (:func:`task_permission`, set by
   :class:`netsim.sweep.executor.DaskExecutor`): the worker's own environment and config are not the user's;
3. the environment variable ``NETSIM_ALLOW_PLUGINS`` (``1``/``true``/``yes`` allow, ``0``/``false``/``no``
   refuse); ``--allow-plugins`` sets it for the worker processes of a batch or a sweep;
4. the per-user file ``$XDG_CONFIG_HOME/netsim/config.toml`` (default ``~/.config/netsim/config.toml``) with
   ``allow_plugins = true``.

Otherwise plugin files are refused: validation reports "this scenario loads code from <file>; rerun with
--allow-plugins if you trust it".
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
from pathlib import Path
from typing import Iterator

__all__ = ["ENV_VAR", "config_path", "plugins_allowed", "scenario_folder", "task_permission", "validating"]

#: Environment variable that allows (or refuses) plugin files.
ENV_VAR = "NETSIM_ALLOW_PLUGINS"

_log = logging.getLogger(__name__)
_YES = {"1", "true", "yes", "on"}
_NO = {"0", "false", "no", "off", ""}
#: The permission a submitted task carries (None: none carried; this process's own settings apply).
_TASK: contextvars.ContextVar[bool | None] = contextvars.ContextVar("netsim_task_plugins", default=None)
#: The folder of the scenario file being validated (None: a mapping, or no validation running).
_FOLDER: contextvars.ContextVar[Path | None] = contextvars.ContextVar("netsim_scenario_folder", default=None)


def config_path() -> Path:
    """The per-user config file: ``$XDG_CONFIG_HOME/netsim/config.toml`` or ``~/.config/netsim/config.toml``."""
    root = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(root) / "netsim" / "config.toml"


def _from_config() -> bool:
    import tomllib

    path = config_path()
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        return False
    except (OSError, tomllib.TOMLDecodeError) as exc:
        _log.warning("ignoring %s: %s", path, exc)
        return False
    value = data.get("allow_plugins", False)
    if not isinstance(value, bool):
        _log.warning("ignoring allow_plugins in %s: write allow_plugins = true or false", path)
        return False
    return value


def plugins_allowed(explicit: bool | None = None) -> bool:
    """True when plugin files may run: ``explicit`` if given, else the permission the running task carries
    (:func:`task_permission`), else the environment, else the user's config."""
    if explicit is not None:
        return bool(explicit)
    carried = _TASK.get()
    if carried is not None:
        return carried
    env = os.environ.get(ENV_VAR)
    if env is not None:
        text = env.strip().lower()
        if text in _YES:
            return True
        if text not in _NO:
            _log.warning("ignoring %s=%r: use 1 or 0", ENV_VAR, env)
        return False
    return _from_config()


@contextlib.contextmanager
def task_permission(allowed: bool) -> Iterator[None]:
    """Within the block (this thread or task only), plugin files may run exactly when ``allowed``: the decision of
    the user who submitted the work, carried to a worker process whose environment and config are someone else's."""
    token = _TASK.set(bool(allowed))
    try:
        yield
    finally:
        _TASK.reset(token)


@contextlib.contextmanager
def validating(allowed: bool | None, folder: Path | None) -> Iterator[None]:
    """While a scenario is validated: the caller's explicit permission (None: the settings above decide) and the
    folder of its file, for plugin parameters that name code files (an FMU plant, :mod:`netsim.plant.fmu`)."""
    token = _FOLDER.set(folder)
    try:
        if allowed is None:
            yield
        else:
            with task_permission(allowed):
                yield
    finally:
        _FOLDER.reset(token)


def scenario_folder() -> Path:
    """The folder relative file names in a scenario's parameters are read from: the scenario file's during
    validation (:func:`validating`), else the working folder."""
    return _FOLDER.get() or Path.cwd()
