"""The whole-log fault detector: ``tlm train`` fits it on labelled flights, ``tlm detect`` runs
it on any ArduPilot log.

| module | job |
| --- | --- |
| :mod:`.channels` | the evidence a log carries, as channels on one 10 Hz grid (causal alignment) |
| :mod:`.features` | trailing 2 s / 10 s window statistics of each channel |
| :mod:`.data` | logs for training (any ``tlm process`` input) and detection (any log) |
| :mod:`.model` | the XGBoost detector, saved as manifest + UBJSON weights (no pickle) |
| :mod:`.train` | fitting, held-out scores, the manifest |
| :mod:`.predict` | per-row probabilities; faults found (persistence 1 s) |
| :mod:`.run`, :mod:`.plots` | ``tlm detect``'s outputs: summary.csv, predictions, timeline.png |
"""
