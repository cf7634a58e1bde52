"""A ``state_feedback`` program's ``estimator:`` and ``law:`` blocks as typed, frozen specs.

``estimator: {type: kalman, Q: ..., R: ...}`` validates into :data:`EstimatorSpec`: a pydantic union discriminated
on ``type``, whose members are netsim's own parts (:data:`~netsim.control.parts.BUILTIN_ESTIMATORS`: the part's
``Params`` with its ``type``, frozen) and, for any other name, a :class:`RegisteredPartSpec` (the registered
part, its parameters validated with its ``Params``); :data:`LawSpec` likewise. The scenario's one validation
checks the block, every error at its YAML path (``...params.estimator.Q``, ``...params.law.type``), and a block
dumps as it was written (the resolved scenario keeps the user's text).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any, ClassVar, Literal, TypeAlias, Union, cast

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    PlainSerializer,
    PlainValidator,
    PrivateAttr,
    Tag,
    WithJsonSchema,
    create_model,
    model_serializer,
    model_validator,
)

from netsim.control.parts import BUILTIN_ESTIMATORS, BUILTIN_LAWS
from netsim.distributions import TAG_MARK
from netsim.errors import ConfigError

__all__ = ["EstimatorSpec", "LawSpec", "PartSpec", "RegisteredPartSpec"]


class PartSpec(BaseModel):
    """A validated ``{type: NAME, its parameters}`` block of netsim's own parts: the part's ``Params`` with its
    ``type``, frozen. It dumps as it was written (the resolved scenario shows the block as given)."""

    model_config = ConfigDict(frozen=True)
    _given: Any = PrivateAttr(None)
    #: The part class (set on each generated spec model).
    part: ClassVar[Any] = None
    if TYPE_CHECKING:  # the part's name: a Literal field of each generated spec model (_spec_model)
        type: str

    @property
    def params(self) -> Any:
        """The parameters ``build`` takes: the spec itself (a subclass of the part's ``Params``)."""
        return self

    @property
    def given(self) -> Any:
        """The block as written (``type`` included)."""
        return self._given

    @model_validator(mode="wrap")
    @classmethod
    def _keep_given(cls, data: Any, handler: Any) -> Any:
        spec = handler(data)
        if spec._given is None:
            spec._given = copy.deepcopy(data) if isinstance(data, dict) else data
        return spec

    @model_serializer(mode="plain")
    def _as_given(self) -> Any:
        return copy.deepcopy(self._given)


@dataclass(frozen=True, eq=False)
class RegisteredPartSpec:
    """A validated block naming a part registered by a plugin (not one of netsim's own): its ``type``, the part,
    and its parameters validated with the part's ``Params`` (the raw mapping when it declares none)."""

    type: str
    part: Any
    params: Any
    given: dict[str, Any]


def _spec_model(kind: str, name: str, part: Any) -> type[PartSpec]:
    title = kind.capitalize() + "".join(w.capitalize() for w in name.split("_"))  # EstimatorSteadyStateKalman
    type_field: Any = (Literal[name], Field(description=f"'{name}'"))  # a Literal of a run-time name
    model = cast("type[PartSpec]", create_model(title, __base__=(part.Params, PartSpec), __module__=__name__,
                                                type=type_field))
    model.part = part
    return model


def _registered(kind: str, field: str, example: str) -> Any:
    """The validator of a block naming a registered part that is not one of netsim's own."""
    from pydantic_core import InitErrorDetails, PydanticCustomError, ValidationError

    def validate(data: Any) -> RegisteredPartSpec:
        if isinstance(data, RegisteredPartSpec):
            return data
        if not isinstance(data, dict):
            raise ValueError(f"{field} is a mapping {{type: NAME, its parameters}} (e.g. {{type: {example}}}), got "
                             f"{str(data)[:60]!r}")
        name = data.get("type")
        if not isinstance(name, str):
            raise ValueError(f"{field} needs a 'type' (e.g. 'type: {example}')")
        from netsim import registry

        try:
            part = registry.lookup(kind, name)
        except ConfigError as exc:
            raise ValidationError.from_exception_data(field, [InitErrorDetails(
                type=PydanticCustomError("unknown_part", "{text}", {"text": exc.message}), loc=("type",),
                input=name)]) from None
        values = {k: v for k, v in data.items() if k != "type"}
        model = registry.params_model(part)
        params = model.model_validate(values) if model is not None else values
        return RegisteredPartSpec(type=name, part=part, params=params, given=copy.deepcopy(data))

    return validate


def _part_union(kind: str, field: str, example: str, builtins: dict[str, Any]) -> Any:
    """``{type: NAME, ...}`` as a pydantic union discriminated on ``type``: netsim's own parts by their tags, any
    other name as a registered part (validated with its registered ``Params``)."""
    members = [Annotated[_spec_model(field, name, part), Tag(f"{TAG_MARK}{name}")] for name, part in builtins.items()]
    members.append(Annotated[RegisteredPartSpec, PlainValidator(_registered(kind, field, example)),
                             PlainSerializer(lambda spec: copy.deepcopy(spec.given)), Tag(f"{TAG_MARK}registered")])

    def tag(data: Any) -> str:
        name = data.get("type") if isinstance(data, dict) else getattr(data, "type", None)
        return f"{TAG_MARK}{name}" if name in builtins and not isinstance(data, RegisteredPartSpec) else \
            f"{TAG_MARK}registered"

    return Annotated[Union[tuple(members)], Discriminator(tag),  # noqa: UP007 - a runtime-built union
                     WithJsonSchema({"type": "object"})]


if TYPE_CHECKING:  # the unions are built at run time; what they validate into is one of these
    EstimatorSpec: TypeAlias = Union[PartSpec, RegisteredPartSpec]
    LawSpec: TypeAlias = Union[PartSpec, RegisteredPartSpec]
else:
    #: ``estimator: {type: NAME, ...}``: one of :data:`BUILTIN_ESTIMATORS` or a registered estimator, typed.
    EstimatorSpec = _part_union("estimator", "estimator", "kalman", BUILTIN_ESTIMATORS)
    #: ``law: {type: NAME, ...}``: one of :data:`BUILTIN_LAWS` or a registered controller, typed.
    LawSpec = _part_union("controller", "law", "lqr", BUILTIN_LAWS)
