"""What a per-table detector's manifest says (:mod:`.table_model`): its window model, its
window settings and the feature columns they imply, and whether a manifest holds them all.
Kept apart so that loading a model (:mod:`.model`) needs none of the training code."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["TABLE_MODELS", "check_table_manifest", "check_table_model", "table_feature_names",
           "window_spec_of"]

#: The window models ``tlm train --models`` can save (``tlm evaluate``'s names).
TABLE_MODELS: tuple[str, ...] = ("WindowHGB", "WindowHGB60", "CentredHGB")


def check_table_model(model: str) -> None:
    """Raise :class:`~.data.DetectError` unless ``model`` is one of :data:`TABLE_MODELS`."""
    from tlm_process.detect.data import DetectError

    if model not in TABLE_MODELS:
        raise DetectError(f"--models: {model} cannot be saved; choose from "
                          f"{', '.join(TABLE_MODELS)} (the paper's other classifiers are "
                          "scikit-learn estimators that save only as pickles)")


def window_spec_of(manifest: dict[str, Any]) -> Any:
    """The :class:`tlm_process.evaluate.temporal.WindowFeatures` of a per-table manifest."""
    from tlm_process.evaluate.temporal import WindowFeatures

    w = manifest["window"]
    return WindowFeatures(tuple(float(s) for s in w["seconds"]),
                          {k: float(v) for k, v in (w.get("circular") or {}).items()},
                          bool(w.get("centred", False)))


def table_feature_names(manifest: dict[str, Any]) -> list[str]:
    """The window-feature columns a per-table model's manifest implies."""
    table = manifest["table"]
    feats = [c.split(".", 1)[1] for c in manifest["channels"] if c.startswith(f"{table}.")]
    return window_spec_of(manifest).names(feats)


def check_table_manifest(man: dict[str, Any], features: Sequence[str]) -> str | None:
    """Why a per-table manifest is unusable (None when it is fine)."""
    if man.get("model") not in TABLE_MODELS or not isinstance(man.get("table"), str):
        return "a per-table model needs one of the window models and its table"
    try:
        if table_feature_names(man) != list(features):
            return "its feature columns differ from this tlm's for its window model"
    except (KeyError, TypeError, ValueError, AttributeError):
        return "its window settings are missing or invalid"
    ranges = (man.get("scaler") or {}).get("ranges") or {}
    if set(ranges) != {c.split(".", 1)[1] for c in man.get("channels") or []}:
        return "its scaler does not cover its features"
    return None
