"""The pydantic models a field's type holds, with the key suffix that reaches each one.

Shared by the scenario reference (:mod:`netsim.cli.docs`) and the JSON Schema (:mod:`netsim.cli.file_schema`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Union, get_args, get_origin

if TYPE_CHECKING:
    from pydantic import BaseModel

__all__ = ["models_in"]


def models_in(tp: Any) -> list[tuple[str, type[BaseModel]]]:
    """``(suffix, model)`` for the pydantic models a container field holds: ``.<name>`` for dict values,
    ``[]`` for list items; a union gives each member."""
    from pydantic import BaseModel

    origin = get_origin(tp)
    if origin is dict:
        return [(".<name>" + s, m) for s, m in models_in(get_args(tp)[1])]
    if origin is list:
        return [("[]" + s, m) for s, m in models_in(get_args(tp)[0])]
    if origin is Union or type(tp).__name__ == "UnionType":
        return [pair for arg in get_args(tp) if arg is not type(None) for pair in models_in(arg)]
    if get_origin(tp) is not None and hasattr(tp, "__metadata__"):  # Annotated[...]
        return models_in(get_args(tp)[0])
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return [("", tp)]
    return []
