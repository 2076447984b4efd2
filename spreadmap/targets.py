"""The targets: what a case measures that the surrogate models and the maps draw, held in one place.

Each target is one ``Target`` in ``REGISTRY`` (in the order the table, the surrogate's ``auto``
targets and the figures list them): its column name, its labels, its unit, the column of its
stated noise SD, the column of the count its counting noise rests on (None for the layer
measures, whose SD is a block jackknife), and its kind (``base``: MFR and PD, the two targets every
analysis has; ``layer``: the layer-quality measures, modelled when the table has them).

Every reader asks here: the metrics (the table's target and SD columns, ``metrics.case``; the SD
columns scaled by the noise calibration, ``metrics.noise``), the surrogate (``surrogate.settings``:
the ``auto`` targets; ``surrogate.plots``: their names), the maps (``maps.style``: labels; the
machine map's y axis, ``maps.grids.choose_machine_y``), the decisions and the explorer. Adding a
layer measure: its code in ``metrics`` (``metrics.case.measure`` writes its value and SD) and one
``Target`` here (docs/guide/04-surrogate-and-maps.md, "Adding a layer measure"); the schema's lists of target names
are checked against ``REGISTRY`` by tests/test_targets.py.
"""
from __future__ import annotations

from dataclasses import dataclass

KINDS = ("base", "layer")


@dataclass(frozen=True)
class Target:
    """One target of the results table.

    Parameters
    ----------
    name : str
        Its column in the results table (and its key in the config: tolerances, noise factors).
    label : str
        Its axis label without the unit (e.g. ``mass flow rate MFR``).
    short : str
        Its short label, in titles and legends of the maps (e.g. ``MFR``).
    unit : str
        Its unit as written in brackets on an axis (``-``: dimensionless).
    sd_column : str
        The column of a case's stated noise SD of it.
    count_column : str or None
        The column of the count its counting noise rests on (spheres passed, spheres in the
        layer); None where its SD is not a counting SD.
    kind : str
        ``base`` (MFR, PD: every analysis has them) or ``layer`` (a layer-quality measure).
    phrase : str
        Its name in running text on the surrogate's figures (e.g. ``layer thickness / h``).
    definition : str or None
        What the measure is, drawn on a map whose axis shows it where its name alone can be
        misread; None: nothing drawn.
    """

    name: str
    label: str
    short: str
    unit: str
    sd_column: str
    count_column: str | None
    kind: str
    phrase: str
    definition: str | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"target {self.name!r}: kind {self.kind!r} is not one of {KINDS}")

    @property
    def axis_label(self) -> str:
        """The axis label with its unit, e.g. ``mass flow rate MFR [-]``."""
        return f"{self.label} [{self.unit}]"


def _register(*targets: Target) -> dict[str, Target]:
    return {t.name: t for t in targets}


# old target names -> their names now; the old name (and a column it starts, e.g. `<old>_sd`) is still
# read: a table's columns by spreadmap.records.current_columns, a config's lists and keys by
# spreadmap.config.renamed_targets (issue 52: the layer fill was called `layer_packing`, a name that
# read as a bulk packing fraction while it reached 0.975)
RENAMED: dict[str, str] = {"layer_packing": "layer_fill"}

LAYER_FILL = ("layer fill = solid volume / volume between the floor (a rough floor's tops) and the layer's "
              "upper surface;\nnot a bulk packing fraction: a monolayer reads 0.80, spheres sunk in a rough "
              "floor's hollows up to 1,\nand it falls towards 0.74 (close packing) only as the layer grows many "
              "diameters thick")  # numbers: tests/metrics/test_layer.py

REGISTRY: dict[str, Target] = _register(
    Target("mfr", "mass flow rate MFR", "MFR", "-", "mfr_sd", "n_passed", "base", "MFR"),
    Target("pd", "packing density PD", "PD", "-", "pd_sd", "n_pd", "base", "PD"),
    Target("layer_fill", "layer fill: solid / volume under its surface", "layer fill", "-", "layer_fill_sd",
           None, "layer", "layer fill", LAYER_FILL),
    Target("coverage", "floor coverage", "coverage", "-", "coverage_sd", None, "layer", "coverage"),
    Target("roughness_d", "surface roughness / d", "roughness/d", "-", "roughness_d_sd", None, "layer",
           "roughness / d"),
    Target("thickness_ratio", "layer thickness / h", "thickness/h", "-", "thickness_ratio_sd", None, "layer",
           "layer thickness / h"),
)


def names(kind: str | None = None) -> tuple[str, ...]:
    """The registered targets' names, in registry order; `kind` given: only that kind's."""
    if kind is not None and kind not in KINDS:
        raise ValueError(f"target kind {kind!r} is not one of {KINDS}")
    return tuple(n for n, t in REGISTRY.items() if kind is None or t.kind == kind)


def get(name: str) -> Target:
    """The registered target `name`; a ValueError naming the registered ones if there is none."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise ValueError(f"no target {name!r} in spreadmap.targets.REGISTRY (registered: {list(REGISTRY)})") from None


def current_name(name: str) -> str:
    """The name now of a column or a target named under an old name (``RENAMED``).

    Parameters
    ----------
    name : str
        A column of a table or a target's name in a config, e.g. ``layer_packing`` or
        ``layer_packing_sd``.

    Returns
    -------
    str
        `name` with an old target name at its start replaced by the new one (``layer_packing_sd``
        -> ``layer_fill_sd``); any other name as it is.
    """
    for old, new in RENAMED.items():
        if name == old or name.startswith(old + "_"):
            return new + name[len(old):]
    return name


def sd_columns() -> tuple[str, ...]:
    """The stated noise SD columns of every registered target, in registry order."""
    return tuple(t.sd_column for t in REGISTRY.values())


def columns() -> tuple[str, ...]:
    """Every column the registered targets put in a case's row: each target's value, its SD and
    its count (where it has one)."""
    out = []
    for t in REGISTRY.values():
        out += [t.name, t.sd_column] + ([t.count_column] if t.count_column else [])
    return tuple(out)


def axis_label(name: str) -> str:
    """The axis label (with unit) of target `name`; an unregistered column: its name."""
    return REGISTRY[name].axis_label if name in REGISTRY else name


def short(name: str) -> str:
    """The short label of target `name`; an unregistered column: its name."""
    return REGISTRY[name].short if name in REGISTRY else name


def phrase(name: str) -> str:
    """The name of target `name` in running text on the surrogate's figures; unregistered: its name."""
    return REGISTRY[name].phrase if name in REGISTRY else name


def definition(name: str) -> str | None:
    """What target `name` is, where its name alone can be misread (drawn on a map whose axis shows
    it); None for the others and for an unregistered column."""
    return REGISTRY[name].definition if name in REGISTRY else None
