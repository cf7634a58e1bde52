"""Case-study models: plants, estimators, controllers and task programs registered by name.

Importing this package registers every case study with :mod:`netsim.registry`.
"""

from __future__ import annotations

import importlib

_CASE_STUDIES = ["models.dc_servo", "models.hdd", "models.cart", "models.pendulum", "models.unicycle"]

for _name in _CASE_STUDIES:
    try:
        importlib.import_module(_name)
    except ModuleNotFoundError as _exc:  # a case study not written yet
        if _exc.name != _name:
            raise
