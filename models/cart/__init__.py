"""The quantized-encoder cart of Henningsson & Cervin: plant, five controllers, metrics, JMAP, programs.

Importing the package registers the plant ``cart``, the programs ``cart_encoder_isr`` and
``cart_controller``, the metric ``cart`` and the report ``cart``.
"""

from __future__ import annotations

import importlib

from models.cart import controllers, estimators, jmap, metrics, tuning  # noqa: F401

for _mod in ("models.cart.plant", "models.cart.programs", "models.cart.report"):
    try:
        importlib.import_module(_mod)
    except ModuleNotFoundError as _exc:  # a netsim part not there yet
        if _exc.name not in (_mod, "netsim.plant", "netsim.io", "netsim.kernel"):
            raise

__all__ = ["controllers", "estimators", "jmap", "metrics", "tuning"]
