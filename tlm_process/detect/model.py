"""A saved detector: a model folder whose loading runs no code from its files.

``MODEL/manifest.json`` (format :data:`MODEL_FORMAT`) says everything but the trees: the tlm
version, the channels (with units and the log columns they need), the feature columns, the
classes (labels and names), the options it was trained with, the training data's summary and
held-out scores, and the SHA-256 of the weights. ``MODEL/booster.ubj`` holds the trees in
XGBoost's own Universal Binary JSON format, loaded with ``xgboost.Booster.load_model`` from
bytes: JSON data, no pickle, nothing executed. :func:`load_detector` checks the manifest, that
the weights file is UBJSON (a pickle starts with byte 0x80 and is refused unread), and its
hash, before XGBoost sees it.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tlm_process.detect.data import DetectError

__all__ = ["MODEL_FORMAT", "MODEL_VERSION", "WEIGHTS_FILE", "Detector", "load_detector"]

MODEL_FORMAT = "tlm.detector"
MODEL_VERSION = 1
WEIGHTS_FILE = "booster.ubj"
MANIFEST_FILE = "manifest.json"
#: A pickle stream starts with the PROTO opcode 0x80 (protocol 2 and later) or an opcode
#: byte of protocols 0/1; UBJSON and JSON objects start with "{".
_UBJ_FIRST = b"{"


@dataclass
class Detector:
    """A fitted detector: ``channels`` it reads (:mod:`.channels`), ``features`` (all
    feature columns) and ``columns`` (the indices among them the trees use: the ones that
    varied in training), ``classes`` (label per output column), the XGBoost ``booster`` and
    the ``manifest`` (what :meth:`save` writes, weights hash aside)."""

    channels: list[str]
    features: list[str]
    columns: np.ndarray
    classes: list[int]
    booster: Any
    manifest: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def fit(cls, X: np.ndarray, y: np.ndarray, channels: Sequence[str],
            features: Sequence[str], *, sample_weight: np.ndarray | None = None,
            rounds: int = 100, min_child_weight: float = 20.0, seed: int = 0,
            n_jobs: int = 1) -> Detector:
        """Fit on ``X`` (rows x ``features``) with labels ``y``. XGBoost histogram boosting
        (64 bins a column): ``rounds`` rounds of one tree per class, learning rate 0.2,
        depth 5, a random 20 % of the columns per tree (a channel's window statistics are
        near copies of each other), L2 1 on leaf values, a leaf's summed hessian at least 20
        (``min_child_weight``: no leaf for a handful of rows of one rare event, where a
        spurious column would split them off: on the 17 reference SITL logs, three booster
        seeds, every fault named in 17/17/16 logs and pooled row macro-F1 0.889/0.951/0.882
        against 16/16/- and 0.850/-/- with XGBoost's default 1; a training set of a few
        flights needs a smaller one); columns with one value in every row are left out
        (they can never split). A single class: nothing is fitted, that class is predicted
        everywhere."""
        import xgboost as xgb

        X = np.asarray(X, dtype=np.float32)
        same = np.ones(X.shape[1], dtype=bool)
        if len(X):
            both_nan = np.isnan(X).all(axis=0)
            same = both_nan | np.all((X == X[:1]) | (np.isnan(X) & np.isnan(X[:1])), axis=0)
        columns = np.flatnonzero(~same)
        classes, code = np.unique(np.asarray(y), return_inverse=True)
        booster = None
        if len(classes) > 1:
            dm = xgb.QuantileDMatrix(X[:, columns], label=code, weight=sample_weight,
                                     max_bin=64, nthread=n_jobs)
            booster = xgb.train(
                {"objective": "multi:softprob", "num_class": len(classes),
                 "tree_method": "hist", "max_depth": 5, "eta": 0.2,
                 "colsample_bytree": 0.2, "lambda": 1.0, "min_child_weight": min_child_weight,
                 "nthread": n_jobs, "seed": seed, "max_bin": 64},
                dm, num_boost_round=rounds)
        return cls(list(channels), list(features), columns, [int(c) for c in classes],
                   booster)

    @property
    def kind(self) -> str:
        """``"whole-log"`` (:mod:`.channels`), or the window model of a per-table detector
        (:mod:`.table_model`)."""
        return str(self.manifest.get("model", "whole-log"))

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Class probabilities (rows x :attr:`classes`)."""
        import xgboost as xgb

        X = np.asarray(X, dtype=np.float32)
        if self.booster is None:
            return np.ones((len(X), 1))
        dm = xgb.DMatrix(X[:, self.columns], nthread=int(self.manifest.get("n_jobs", 1)))
        return self.booster.predict(dm).reshape(len(X), len(self.classes))

    # ----------------------------------------------------------------------------------
    # Saving and loading
    # ----------------------------------------------------------------------------------

    def save(self, folder: str | os.PathLike) -> Path:
        """Write ``folder/booster.ubj`` and ``folder/manifest.json`` (the manifest last: a
        folder without one is not a model)."""
        d = Path(folder)
        d.mkdir(parents=True, exist_ok=True)
        raw = bytes(self.booster.save_raw("ubj")) if self.booster is not None else b"{}"
        (d / WEIGHTS_FILE).write_bytes(raw)
        man = dict(self.manifest)
        man.update({
            "format": MODEL_FORMAT, "version": MODEL_VERSION,
            "channels": list(self.channels), "features": list(self.features),
            "columns": [int(c) for c in self.columns], "classes": list(self.classes),
            "weights": {"file": WEIGHTS_FILE, "format": "xgboost-ubj",
                        "sha256": hashlib.sha256(raw).hexdigest(),
                        "fitted": self.booster is not None},
        })
        self.manifest = man
        (d / MANIFEST_FILE).write_text(json.dumps(man, indent=1) + "\n")
        return d


def load_detector(folder: str | os.PathLike) -> Detector:
    """The detector saved in ``folder``. Raises :class:`DetectError` (one line) for a folder
    that is not a tlm model, a newer model version, a weights file that is not XGBoost
    UBJSON (a pickle is refused without being read further), or one whose hash differs from
    the manifest's."""
    d = Path(folder)
    if not d.is_dir():
        raise DetectError("no such model folder (make one with tlm train DS --out MODEL)",
                          source=str(d))
    man = _read_manifest(d)
    w = man.get("weights") or {}
    raw = _read_weights(d, w)
    channels = list(man.get("channels") or [])
    features = list(man.get("features") or [])
    _check_inputs(d, man, channels, features)
    columns = np.asarray(man.get("columns") or [], dtype=np.int64)
    classes = [int(c) for c in man.get("classes") or []]
    if not classes or (len(columns) and (columns.min() < 0 or columns.max() >= len(features))):
        raise DetectError("manifest.json's classes or columns are invalid", source=str(d))
    booster = _load_booster(d, raw, len(columns)) if w.get("fitted", True) else None
    return Detector(channels, features, columns, classes, booster, man)


def _read_manifest(d: Path) -> dict[str, Any]:
    """``d/manifest.json``, checked to be a tlm detector of a version this tlm reads."""
    mp = d / MANIFEST_FILE
    try:
        man = json.loads(mp.read_text())
    except FileNotFoundError:
        raise DetectError("no manifest.json: not a tlm model folder", source=str(d)) from None
    except (OSError, ValueError) as exc:
        raise DetectError(f"cannot read manifest.json: {exc}", source=str(d)) from None
    if not isinstance(man, dict) or man.get("format") != MODEL_FORMAT:
        raise DetectError(f"manifest.json is not a tlm detector (format {MODEL_FORMAT!r} "
                          "expected)", source=str(d))
    v = man.get("version")
    if not isinstance(v, int) or isinstance(v, bool) or v > MODEL_VERSION:
        raise DetectError(f"model version {v!r}; this tlm reads versions up to "
                          f"{MODEL_VERSION} (a newer tlm wrote it: update tlm)", source=str(d))
    return man


def _read_weights(d: Path, w: dict[str, Any]) -> bytes:
    """The weights file's bytes, checked to be UBJSON (a pickle is refused unread) with the
    manifest's SHA-256 (``w``: the manifest's ``weights``)."""
    if w.get("format") != "xgboost-ubj" or w.get("file") != WEIGHTS_FILE:
        raise DetectError(f"weights must be XGBoost UBJSON in {WEIGHTS_FILE}", source=str(d))
    try:
        raw = (d / WEIGHTS_FILE).read_bytes()
    except OSError as exc:
        raise DetectError(f"cannot read {WEIGHTS_FILE}: {exc.strerror or exc}",
                          source=str(d)) from None
    if not raw.startswith(_UBJ_FIRST):
        what = "a Python pickle" if raw[:1] == b"\x80" else "not UBJSON"
        raise DetectError(f"{WEIGHTS_FILE} is {what}: refused (tlm loads only XGBoost's "
                          "UBJSON weights, never pickles)", source=str(d))
    if hashlib.sha256(raw).hexdigest() != w.get("sha256"):
        raise DetectError(f"{WEIGHTS_FILE} does not match the manifest's SHA-256 (changed "
                          "after training)", source=str(d))
    return raw


def _check_inputs(d: Path, man: dict[str, Any], channels: list[str],
                  features: list[str]) -> None:
    """Refuse a whole-log model whose channels or feature columns this tlm does not know, or
    a per-table model whose manifest does not hold together."""
    if man.get("model", "whole-log") == "whole-log":
        from tlm_process.detect.channels import CHANNELS
        from tlm_process.detect.features import feature_names

        known = {c.name for c in CHANNELS}
        unknown = [c for c in channels if c not in known]
        if unknown or not channels:
            raise DetectError(f"the model reads channel(s) this tlm does not know: "
                              f"{', '.join(unknown[:5]) or '(none listed)'}", source=str(d))
        if feature_names(channels) != features:
            raise DetectError("the model's feature columns differ from this tlm's for its "
                              "channels (trained by another tlm version: train it again)",
                              source=str(d))
        return
    from tlm_process.detect.table_spec import check_table_manifest

    why = check_table_manifest(man, features)
    if why is not None:
        raise DetectError(f"manifest.json: {why}", source=str(d))


def _load_booster(d: Path, raw: bytes, n_columns: int) -> Any:
    """XGBoost's booster from the checked weights ``raw``, with ``n_columns`` inputs."""
    import xgboost as xgb

    booster = xgb.Booster()
    try:
        booster.load_model(bytearray(raw))
    except xgb.core.XGBoostError as exc:
        first = str(exc).splitlines()[0] if str(exc) else "unreadable"
        raise DetectError(f"cannot load {WEIGHTS_FILE}: {first}", source=str(d)) from None
    if booster.num_features() != n_columns:
        raise DetectError(f"{WEIGHTS_FILE} has {booster.num_features()} inputs, the "
                          f"manifest {n_columns}", source=str(d))
    return booster
