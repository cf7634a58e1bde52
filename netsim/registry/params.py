"""What ``netsim list KIND NAME`` prints: a plugin's parameters read from its nested pydantic ``Params`` model.

:func:`param_rows` turns a model into one :class:`ParamRow` per field (name, type, default, unit, description),
a nested model's fields dotted after it. Units: a field declares its own with
``Field(..., json_schema_extra={"unit": "rad/s"})``; time fields (:data:`netsim.units.Time`, ``Duration``,
``SignedTime``) get :data:`TIME_UNIT` and bit rates ``bit/s``. Nothing here knows a plugin kind or the registry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any, Literal, Union, get_args, get_origin

if TYPE_CHECKING:
    from pydantic import BaseModel

__all__ = ["TIME_UNIT", "ParamRow", "params_model", "param_rows"]


@dataclass(frozen=True)
class ParamRow:
    """One parameter of a plugin's ``Params`` model, as ``netsim list KIND NAME`` prints it.

    ``name`` is dotted for the fields of a nested model (``delay.mean``); ``default`` is ``"required"`` when the
    field has none; ``unit`` is the field's declared unit (``json_schema_extra={"unit": ...}``), ``"time"`` for
    time fields (:data:`TIME_UNIT`: written with a unit, ``20 us``) and ``"bit/s"`` for bit rates (:mod:`netsim.units`).
    """

    name: str
    type: str
    default: str
    unit: str
    description: str


#: The unit :func:`param_rows` gives time fields: they are written with any of these (``20 us``, ``1.5 ms``).
TIME_UNIT = "ns|us|ms|s"


def params_model(obj: Any) -> type[BaseModel] | None:
    """The pydantic model in ``obj.Params`` (the plugin's parameters), or ``None`` when it declares none."""
    from pydantic import BaseModel

    cls = getattr(obj, "Params", None)
    return cls if isinstance(cls, type) and issubclass(cls, BaseModel) else None


def _unit_type(metadata: list[Any]) -> tuple[str, str] | None:
    """``(type, unit)`` of a :mod:`netsim.units` field from its validators, else ``None``."""
    from netsim import units

    known = {units._time: ("time", TIME_UNIT), units._duration: ("duration", TIME_UNIT),
             units._signed: ("signed time", TIME_UNIT), units.parse_bitrate: ("bit rate", "bit/s")}
    for item in metadata:
        func = getattr(item, "func", None)
        if func in known:
            return known[func]
    return None


def _type_name(tp: Any) -> str:
    """A short readable name of a field annotation (``float | None``, ``'fp' | 'edf'``, ``list[duration]``)."""
    origin = get_origin(tp)
    if tp is type(None):
        return "null"
    if origin is Annotated:
        base, *meta = get_args(tp)
        unit = _unit_type(meta)
        return unit[0] if unit else _type_name(base)
    if origin is Literal:
        return " | ".join(repr(a) for a in get_args(tp))
    if origin is Union or type(tp).__name__ == "UnionType":
        return " | ".join(_type_name(a) for a in get_args(tp))
    if origin is not None:
        args = get_args(tp)
        name = getattr(origin, "__name__", str(origin))
        return f"{name}[{', '.join(_type_name(a) for a in args)}]" if args else name
    if isinstance(tp, type):
        return tp.__name__
    return str(tp).replace("typing.", "")


def _default_text(field: Any, unit: str) -> str:
    from pydantic import BaseModel
    from pydantic_core import PydanticUndefined

    if field.default_factory is not None:
        try:
            value = field.default_factory()
        except TypeError:  # a factory that takes the validated data: its value depends on the other fields
            return "(computed)"
    elif field.default is PydanticUndefined:
        return "required"
    else:
        value = field.default
    if value is None:
        return "null"
    if isinstance(value, BaseModel):
        value = value.model_dump(mode="json")
    if unit == TIME_UNIT and isinstance(value, int) and not isinstance(value, bool):
        from netsim.timebase import format_time

        return format_time(value)
    if isinstance(value, str):
        return repr(value)
    return str(value).replace("\n", " ")


def _inner_unit_type(tp: Any) -> tuple[str, str] | None:
    """The :mod:`netsim.units` type inside an annotation (``Duration | None``, ``list[Duration]``), if any."""
    if get_origin(tp) is Annotated:
        return _unit_type(list(get_args(tp)[1:]))
    for arg in get_args(tp):
        found = _inner_unit_type(arg)
        if found is not None:
            return found
    return None


def _nested_model(tp: Any) -> type[BaseModel] | None:
    """The one pydantic model a field holds (``Model`` or ``Model | None``), whose fields are listed too."""
    from pydantic import BaseModel

    args = [a for a in get_args(tp) if a is not type(None)] if get_origin(tp) in (Union,) or \
        type(tp).__name__ == "UnionType" else [tp]
    if len(args) == 1 and isinstance(args[0], type) and issubclass(args[0], BaseModel):
        return args[0]
    return None


def param_rows(model: type[BaseModel], prefix: str = "", _depth: int = 0) -> list[ParamRow]:
    """The parameters of the pydantic ``model`` (a plugin's ``Params``), nested models' fields dotted.

    Parameters
    ----------
    model
        A pydantic model class.
    prefix
        Prepended to every name (``"delay."`` for a nested model's fields).

    Returns
    -------
    list[ParamRow]
        One row per field in declaration order; the fields of a field whose type is one model follow it.
    """
    rows: list[ParamRow] = []
    for name, field in model.model_fields.items():
        shown = field.alias or name
        unit_type = _unit_type(field.metadata) or _inner_unit_type(field.annotation)
        type_text = _type_name(field.annotation)
        if _unit_type(field.metadata):  # Annotated at the top level: pydantic moved the validator to metadata
            type_text = _unit_type(field.metadata)[0]  # type: ignore[index]
        extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
        unit = str(extra.get("unit", "")) or (unit_type[1] if unit_type else "")
        description = " ".join((field.description or "").split())
        rows.append(ParamRow(prefix + shown, type_text, _default_text(field, unit), unit, description))
        nested = _nested_model(field.annotation)
        if nested is not None and _depth < 3:
            rows += param_rows(nested, prefix=f"{prefix}{shown}.", _depth=_depth + 1)
    return rows
