"""Evaluation of TLM data sets (paper §5): the ten Weka classifiers of Table 11 as scikit-learn
estimators, the paper's row-image CNN, a time-window model, Weka-style metrics, flight-level
and row-level splits, and transfer to real SITL logs. See ``docs/evaluation.md``.

Typical use::

    from tlm_process.evaluate import evaluate, load_dataset

    ds = load_dataset("ds")
    results = evaluate(ds, tables=["GPS"], models=["RandomForest", "WindowHGB"], seed=0)
    results["GPS"]["RandomForest"]["macro_f1"]

Names are imported lazily (on first use), so that importing a submodule (the ``tlm evaluate``
command, :mod:`tlm_process.commands.evaluate`, does for ``--help``) does not pull in
scikit-learn or torch.
"""

from __future__ import annotations

from tlm_process._lazy import lazy_exports

_EXPORTS: dict[str, str] = {
    "data": "EvalDataset EvaluateError load_dataset load_transfer",
    "metrics": "CLASS_NAMES classification_metrics confusion_matrix format_confusion "
               "format_results_table plot_confusion",
    "models": "ALL_MODELS PAPER_MODELS AdaBoostM1 J48 OneR WekaNaiveBayes make_model",
    "runner": "evaluate",
    "splits": "Fold flight_folds random_folds",
    "temporal": "WindowFeatures window_features",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
