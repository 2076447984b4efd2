"""The saved surrogate: one fitted model per target, the cases it was trained on, its metadata.

The file is a joblib pickle (load only files you trust); a JSON sidecar beside it holds the
metadata for people and tools, and the SHA-256 of the file as it was saved. ``load_model`` turns
every way a file can fail to be a surrogate of this version (missing, truncated, corrupt, foreign,
older format) into one ``ModelFileError`` line; a truncated or corrupted file (one that does not
unpickle, or whose bytes differ from the sidecar's checksum: a flipped byte in a weight array
unpickles fine) is a ``CorruptModelError``, which a Snakemake job moves aside so that the next run
retrains it (spreadmap.records).
"""
from __future__ import annotations

import hashlib
import io
import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..design import NAMES, TARGETS
from ..files import atomic_path
from ..records import CorruptFileError

FORMAT = "spreadmap-surrogate/2"


class ModelFileError(ValueError):
    """A model file that cannot be used: the message says which file and why, in one line."""


class CorruptModelError(ModelFileError, CorruptFileError):
    """A model file that is truncated or corrupted (not merely foreign or of an older format)."""


@dataclass
class SurrogateModel:
    """Per-target fitted models (``models.GPModel`` or ``models.MLPModel``) and the training cases."""

    targets: tuple
    models: dict
    train_X: np.ndarray                 # usable cases' inputs, physical units, NAMES order
    design_low: np.ndarray
    design_high: np.ndarray
    metadata: dict = field(default_factory=dict)
    format: str = FORMAT
    names: tuple = NAMES
    correction: object = None           # spreadmap.surrogate.correction.Correction, or None (as the preset reads)

    # ---- where the data are -------------------------------------------------------------------
    def unit(self, X) -> np.ndarray:
        return (np.asarray(X, float) - self.design_low) / (self.design_high - self.design_low)

    def spacing(self) -> float:
        """Median distance from a training case to its nearest other case (unit design cube)."""
        U = self.unit(self.train_X)
        d, _ = cKDTree(U).query(U, k=2)
        return float(np.median(d[:, 1]))

    def data_distance(self, X) -> np.ndarray:
        """Distance to the nearest training case, in units of the cases' median spacing."""
        d, _ = cKDTree(self.unit(self.train_X)).query(self.unit(X), k=1)
        return d / self.spacing()

    def outside_design(self, X) -> np.ndarray:
        X = np.asarray(X, float)
        return (X < self.design_low) | (X > self.design_high)

    # ---- predictions --------------------------------------------------------------------------
    def predict_stats(self, X, corrected: bool = True) -> dict:
        """target -> (mean, model SD, SD of a new DEM run) at X (n, 4); with a ``correction`` (and
        ``corrected``), as the finer preset would read them (spreadmap.surrogate.correction)."""
        out = {t: self.models[t].predictive(np.asarray(X, float)) for t in self.targets}
        if corrected and self.correction is not None:
            out = {t: self.correction.stats(t, *v) for t, v in out.items()}
        return out

    def draws(self, X, n: int, seed: int = 0, targets=None) -> dict:
        """target -> (n, len(X)) draws of the mean function (GP posterior or MLP members)."""
        rng = np.random.default_rng(seed)
        out = {t: self.models[t].draws(np.asarray(X, float), n, rng) for t in (targets or self.targets)}
        if self.correction is not None:
            out = {t: self.correction.draws(t, v, rng) for t, v in out.items()}
        return out

    def kind(self, target: str) -> str:
        return self.models[target].kind

    def __call__(self, points) -> np.ndarray:
        """The package's predictor convention: (n, 4) physical -> (n, 2) mean MFR and PD."""
        X = np.asarray(points, float)
        means = [self.models[t].latent(X)[0] for t in TARGETS]
        if self.correction is not None:
            means = [self.correction.scale(t, m) for t, m in zip(TARGETS, means)]
        return np.column_stack(means)


def sidecar_path(path) -> Path:
    path = Path(path)
    return path.with_suffix(".json") if path.suffix == ".joblib" else path.with_name(path.name + ".json")


def save_model(model: SurrogateModel, path) -> tuple[Path, Path]:
    """joblib file of the model and a JSON sidecar of its metadata and the file's SHA-256
    (`model_sha256`), each written atomically.

    Parameters
    ----------
    model : SurrogateModel
        The fitted surrogate.
    path : pathlib.Path or str
        The model file (e.g. results/surrogate/model.joblib); the sidecar is beside it
        (``sidecar_path``: ``.joblib`` replaced by ``.json``, else ``.json`` appended).

    Returns
    -------
    path, sidecar : tuple of pathlib.Path
        The model file and its sidecar.

    Raises
    ------
    ValueError
        If the metadata holds a NaN or infinity (JSON without them).
    OSError
        If a file cannot be written.
    """
    import joblib

    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            joblib.dump(model, fh)
        digest = hashlib.sha256(tmp.read_bytes()).hexdigest()
    side = sidecar_path(path)
    with atomic_path(side) as tmp:
        tmp.write_text(json.dumps({**model.metadata, "model_sha256": digest}, indent=2, sort_keys=True,
                                  allow_nan=False) + "\n")
    return path, side


_RETRAIN = "move it aside and retrain it: `snakemake results/surrogate/model.joblib`"


def _saved_sha256(path: Path) -> str | None:
    """The checksum the sidecar recorded when the model was saved; None without one (a sidecar
    that is missing, unreadable or from before the checksum: the metadata is not the model)."""
    try:
        value = json.loads(sidecar_path(path).read_text()).get("model_sha256")
    except (OSError, ValueError, AttributeError):
        return None
    return value if isinstance(value, str) else None


# modules renamed since models were saved (pickles name a class by its module): old name -> new
RENAMED_MODULES = {"spreadmap.surrogate.noise": "spreadmap.surrogate.noise_sd"}


def _alias_renamed_modules() -> None:
    """Let a model saved before a module's rename load: its old name imports the new module."""
    import importlib
    import sys

    for old, new in RENAMED_MODULES.items():
        sys.modules.setdefault(old, importlib.import_module(new))


def load_model(path) -> SurrogateModel:
    """Load a saved surrogate.

    Any file that is not one (missing, corrupt, foreign, older format) raises ModelFileError with
    a one-line reason; a different scikit-learn version warns. The file is a joblib pickle: load
    only files you trust.

    Parameters
    ----------
    path : pathlib.Path or str
        The model file (``save_model``).

    Returns
    -------
    SurrogateModel
        The saved surrogate.

    Raises
    ------
    ModelFileError
        If the file is missing, does not hold a spreadmap surrogate, or holds one of another
        format.
    CorruptModelError
        (A ModelFileError and a spreadmap.records.CorruptFileError.) If the file does not
        unpickle or its SHA-256 differs from the one its sidecar recorded (truncated or
        corrupted).

    Warns
    -----
    UserWarning
        If the model was trained with another scikit-learn version.
    """
    import joblib
    import sklearn

    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"surrogate model file not found: {path}")
    data = path.read_bytes()
    saved_sha = _saved_sha256(path)
    if saved_sha is not None and hashlib.sha256(data).hexdigest() != saved_sha:
        raise CorruptModelError(path, f"{path} is not the surrogate that was saved: its SHA-256 differs from the "
                                      f"one its sidecar {sidecar_path(path).name} recorded (truncated or corrupted); "
                                      f"{_RETRAIN}")
    _alias_renamed_modules()
    try:
        model = joblib.load(io.BytesIO(data))
    except Exception as error:  # noqa: BLE001  unpickling foreign bytes can raise anything (struct.error, ...)
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise CorruptModelError(path, f"{path} is not a readable spreadmap surrogate ({type(error).__name__}: "
                                      f"{reason[:200]}): truncated or corrupted; {_RETRAIN}") from None
    if not isinstance(model, SurrogateModel):
        raise ModelFileError(f"{path} does not hold a spreadmap surrogate (it holds a {type(model).__name__})")
    if getattr(model, "format", None) != FORMAT:
        raise ModelFileError(f"{path} is a surrogate of format {getattr(model, 'format', '?')!r}, this code reads "
                             f"{FORMAT!r}; retrain it")
    saved = model.metadata.get("versions", {}).get("sklearn")
    if saved and saved != sklearn.__version__:
        warnings.warn(f"{path} was trained with scikit-learn {saved}, running {sklearn.__version__}; "
                      "predictions may differ", UserWarning, stacklevel=2)
    return model

