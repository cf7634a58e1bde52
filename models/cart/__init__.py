"""The quantized-encoder cart of Henningsson & Cervin: plant, five controllers, metrics, JMAP, programs.

Its modules register the plant ``cart`` (:mod:`~netsim.models.cart.plant`), the programs ``cart_encoder_isr`` and
``cart_controller`` (:mod:`~netsim.models.cart.programs`), the metric ``cart`` (:mod:`~netsim.models.cart.metrics`) and the
report ``cart`` (:mod:`~netsim.models.cart.report`); :func:`netsim.registry.load_plugins` imports every one of them.
"""

from __future__ import annotations

from netsim.models.cart import controllers, estimators, jmap, metrics, tuning

__all__ = ["controllers", "estimators", "jmap", "metrics", "tuning"]
