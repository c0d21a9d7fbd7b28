"""CSV files the project writes name each column's unit in its header, ``name [unit]`` (``[-]``
for pure numbers and labels); readers key the columns by the bare name (``bare``)."""

from __future__ import annotations


def header(names, units: dict[str, str], default: str | None = None) -> list[str]:
    """``name [unit]`` for each name; a name missing from ``units`` gets ``default`` (None:
    KeyError, so a new column cannot go out without its unit)."""
    out = []
    for n in names:
        unit = units.get(n, default)
        if unit is None:
            raise KeyError(f"CSV column {n!r} has no unit")
        out.append(f"{n} [{unit}]")
    return out


def bare(name: str) -> str:
    """The column name without its unit: ``'time [s]'`` -> ``'time'``."""
    return name.split(" [", 1)[0]

