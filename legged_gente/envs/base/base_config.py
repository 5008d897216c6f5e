"""legged_gym-style configuration: nested classes, changed by subclassing, instantiated per run."""

from __future__ import annotations

import copy
import dataclasses
import inspect


class BaseConfig:
    """A config class whose nested classes become (independent) instances when it is constructed.

    Subclass to change a robot or task; construct to get a mutable copy that command-line arguments may
    override without touching the class itself.
    """

    def __init__(self) -> None:
        _instantiate_nested(self)


def _instantiate_nested(obj: object) -> None:
    for name in dir(obj):
        if name.startswith("__"):
            continue
        value = getattr(obj, name)
        if inspect.isclass(value):
            instance = value()
            setattr(obj, name, instance)
            _instantiate_nested(instance)
        elif dataclasses.is_dataclass(value):  # a term record (ObsTerm): each config instance gets its own copy
            setattr(obj, name, dataclasses.replace(value))
        elif isinstance(value, (list, dict, set)):  # an edit in place (cfg.control.stiffness["knee"] = 1) stays in
            setattr(obj, name, copy.deepcopy(value))  # this instance, not in the class and every later config


def class_to_dict(obj: object) -> dict | object:
    """Public attributes of a config instance (recursively) as plain dicts and lists."""
    if not hasattr(obj, "__dict__") and not inspect.isclass(obj):
        return obj
    result = {}
    for name in dir(obj):
        if name.startswith("_"):
            continue
        value = getattr(obj, name)
        if callable(value) and not inspect.isclass(value):
            continue
        if isinstance(value, (list, tuple)):
            result[name] = [class_to_dict(v) for v in value]
        elif hasattr(value, "__dict__") or inspect.isclass(value):
            result[name] = class_to_dict(value)
        else:
            result[name] = value
    return result


def update_from_dict(obj: object, values: dict, path: str = "cfg") -> None:
    """Set attributes of a config instance from a (nested) dict; unknown keys raise with the valid ones."""
    for key, value in values.items():
        if not hasattr(obj, key):
            valid = sorted(k for k in dir(obj) if not k.startswith("_"))
            raise AttributeError(f"{path} has no attribute {key!r}; valid attributes: {valid}")
        current = getattr(obj, key)
        if isinstance(value, dict) and hasattr(current, "__dict__") and not isinstance(current, dict):
            update_from_dict(current, value, f"{path}.{key}")
        else:
            setattr(obj, key, value)
