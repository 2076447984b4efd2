"""The maps' step from the preset that ran to the finest one: a measured factor and its uncertainty.

The main job runs the `default` preset; the fidelity study measures, at paired points and packing
seeds, what `reference` reads against it (spreadlab.paired_factor, docs/fidelity/correction).
Where config `fidelity_correction` gives a target a factor k with an SD s_k (its error at a point the
fidelity study did not run: spreadlab.paired_factor), the saved map
model reports that target as `reference` would read it:

    mean' = k mean,    model SD' = sqrt(k^2 model SD^2 + mean^2 s_k^2 + model SD^2 s_k^2),

(the exact variance of the product of two independent normal quantities; the run SD likewise), and
each posterior draw of the map is multiplied by one draw of k, the same over every point of a map
(the factor is one number, so its error moves the whole map together). The loop's stop rule does
not see it: the map's own error against the DEM of its preset is what sampling can reduce; the
factor's error is what the fidelity study can. Targets without a factor stay as their preset reads
them, and the maps say so.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..design import TARGETS


@dataclass(frozen=True)
class Correction:
    """target -> (factor, its SD); `preset` ran, `reference` is what the factors lead to.

    Parameters
    ----------
    factors : dict
        target -> (factor k, its SD s_k), both dimensionless (reference / preset).
    preset : str
        The preset the cases ran.
    reference : str
        The preset the factors lead to.
    source : str, optional
        Where the factors come from (the config section's ``source``).
    """

    factors: dict
    preset: str
    reference: str
    source: str = ""

    @classmethod
    def from_config(cls, config: dict | None) -> "Correction | None":
        """The config's factors, or None without any, or when they were measured for another preset
        or floor than the config runs (``applies``: then the maps read as their preset does).

        Parameters
        ----------
        config : dict or None
            A config holding a ``fidelity_correction`` section (and the run's ``preset`` and
            ``scene``, when given, to check it applies).

        Returns
        -------
        Correction or None
            The factors of the section's ``targets``, or None.

        Raises
        ------
        ValueError
            If a factor is not > 0 or its SD is negative.
        """
        section = (config or {}).get("fidelity_correction")
        if not section or applies(config) is not None:
            return None
        factors = {t: (float(v["factor"]), float(v["sd"])) for t, v in section.get("targets", {}).items()}
        for t, (k, s) in factors.items():
            if not (k > 0 and s >= 0):
                raise ValueError(f"config fidelity_correction.targets.{t}: factor {k} must be > 0 and sd {s} >= 0")
        preset = section.get("preset") or (config or {}).get("preset", "default")
        return cls(factors, str(preset), str(section.get("reference", "reference")), str(section.get("source", "")))

    def scale(self, target: str, mean):
        """`target`'s mean after its factor (unchanged without one).

        Parameters
        ----------
        target : str
            The target.
        mean : float or numpy.ndarray
            Its mean as the preset reads it (the target's units).

        Returns
        -------
        float or numpy.ndarray
            k x mean, or `mean` when the target has no factor.
        """
        return mean * self.factors[target][0] if target in self.factors else mean

    def stats(self, target: str, mean, model_sd, run_sd):
        """(mean, model SD, run SD) of `target` after its factor; unchanged without one.

        The SDs are those of the product of two independent normal quantities (the module
        docstring).

        Parameters
        ----------
        target : str
            The target.
        mean : array_like
            Its mean as the preset reads it (the target's units).
        model_sd : array_like
            The model's SD (same units).
        run_sd : array_like
            The SD of a new DEM run (same units).

        Returns
        -------
        mean, model_sd, run_sd : tuple
            The three after the factor (numpy arrays), or the inputs unchanged without a factor.
        """
        if target not in self.factors:
            return mean, model_sd, run_sd
        k, s = self.factors[target]
        mean, model_sd, run_sd = (np.asarray(x, float) for x in (mean, model_sd, run_sd))
        return (k * mean, np.sqrt(k**2 * model_sd**2 + (mean**2 + model_sd**2) * s**2),
                np.sqrt(k**2 * run_sd**2 + (mean**2 + run_sd**2) * s**2))

    def draws(self, target: str, draws: np.ndarray, rng) -> np.ndarray:
        """(n, points) draws of the map times one draw of the factor per row.

        Parameters
        ----------
        target : str
            The target.
        draws : numpy.ndarray
            Shape (n, points): draws of the map as the preset reads it.
        rng : numpy.random.Generator
            Draws the factors, normal with mean k and SD s_k.

        Returns
        -------
        numpy.ndarray
            Same shape; `draws` unchanged when the target has no factor.
        """
        if target not in self.factors:
            return draws
        k, s = self.factors[target]
        return draws * rng.normal(k, s, size=(len(draws), 1))

    def label(self, targets=TARGETS) -> str:
        """One line for a map: what the means are, e.g. "`default` corrected to `reference`: MFR x1.031 (SD 0.010)".

        Parameters
        ----------
        targets : sequence of str, optional
            The map's targets; those without a factor are named as the preset reads them.

        Returns
        -------
        str
            The line.
        """
        parts = [f"{t.upper() if t in TARGETS else t} x{k:.3f} (SD {s:.3f})" for t, (k, s) in self.factors.items()]
        rest = [t for t in targets if t not in self.factors]
        text = f"`{self.preset}` corrected to `{self.reference}`: " + ", ".join(parts)
        if rest:
            text += "; " + ", ".join(rest) + f" as `{self.preset}` reads"
        return text

    def attach(self, model) -> None:
        """Make a fitted map model read as `reference` would: set its ``correction`` and record the
        factors in its metadata (``fidelity_correction``: label, factors, source).

        Parameters
        ----------
        model : spreadmap.surrogate.saved_model.SurrogateModel
            The map model, changed in place (its fit is not touched).
        """
        model.correction = self
        model.metadata["fidelity_correction"] = {"label": self.label(model.targets), "factors": self.factors,
                                                 "source": self.source}


def applies(config: dict | None) -> str | None:
    """Why the config's `fidelity_correction` does not apply to the run it configures (measured for
    another preset, floor or powder model), or None when it applies or there is none. Its
    ``surface_energy_j_m2`` absent: measured on dry spheres (every correction before adhesion)."""
    config = config or {}
    section = config.get("fidelity_correction") or {}
    if section.get("preset") not in (None, config.get("preset", section.get("preset"))):
        return f"its factors are for `{section['preset']}`"
    if "scene" in config:
        floor = ((config.get("scene") or {}).get("substrate") or {}).get("kind", "flat")  # the schema's default
        if section.get("floor") not in (None, floor):
            return f"its factors were measured on the {section['floor']} floor"
    if section and "material" in config:
        measured = float(section.get("surface_energy_j_m2", 0.0))
        runs = float((config.get("material") or {}).get("surface_energy_j_m2", 0.0))
        if measured != runs:
            return (f"its factors were measured with surface energy {measured * 1e3:g} mJ/m^2, "
                    f"the run's is {runs * 1e3:g} mJ/m^2")
    return None


def uncorrected_label(preset: str, reference: str = "reference", why: str | None = None) -> str:
    return f"`{preset}` preset, not corrected to `{reference}`" + (f" ({why})" if why else "")
