"""The shape of an optional section of a model file, checked the same way for every section."""

from __future__ import annotations

from typing import Any, Mapping, Sequence


def section_shape_problem(model: Mapping[str, Any], name: str, keys: Sequence[str]) -> str | None:
    """What is wrong with the shape of the optional section ``name``: not an object, or without one of ``keys``
    (the first missing one is named); None when the section is absent or holds them all."""
    section = model.get(name)
    if section is None:
        return None
    if not isinstance(section, Mapping):
        return f"'{name}' must be an object"
    for key in keys:
        if key not in section:
            return f"{name} lacks key '{key}'"
    return None
