"""The calibration loop on plain records, without a database (design-notes: Optuna's pattern).

compare the model with measurements -> see where it fails (``localise``) -> learn which physical
effect is missing (``attribute``) -> add it and watch the error fall (``loop``). ``service/``
stores the loop's state and queues its batteries; a notebook runs it with any batch evaluator.

Modules: ``keys`` (the (test, quantity, condition) key), ``records`` (measured targets, noise),
``parameters`` (design factors as dotted paths, checked against the engine's registry),
``conditions`` (the battery's conditions from the targets), ``evaluators`` (batch evaluators),
``fitting`` (response surfaces of targets), ``calibrate`` (optimum through doe.optimise,
confirmation, polish), ``localise``, ``attribute``, ``verdict``, ``loop``, ``stats``, ``standin``
(closed-form battery with every candidate effect) and ``testbed`` (tier-A hidden-effect cases).
"""
