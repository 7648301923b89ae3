"""The calibration loop on plain records, without a database (design-notes: Optuna's pattern).

compare the model with measurements -> see where it fails (``localise``) -> learn which physical
effect is missing (``attribute``) -> add it and watch the error fall (``automatic``, ``adding``).
``machine`` is the loop itself, one resumable state machine; ``service/`` stores its state and queues
its batteries, ``loop`` drives it in a notebook with any batch evaluator.

The loop: ``machine`` (phases and transitions), ``settings`` (what a loop is asked to do),
``vocabulary`` (phases, run kinds, verdicts, stop reasons), ``state`` (the loop in memory), ``loop``
(the notebook driver), ``replay`` (stored batteries as an evaluator), ``errors``.
Its steps: ``design``, ``fits`` (surfaces once per iteration), ``analysis`` (optimum, surrogate check,
diagnosis plan and ranking), ``polish``, ``report``, ``verdict``, ``automatic``, ``adding``, ``history``.
The pieces they use: ``keys`` (the (test, quantity, condition) key), ``records`` (measured targets,
noise), ``parameters`` (design factors as dotted paths, checked against the engine's registry),
``conditions`` (a run's job and the conditions its targets ask for), ``evaluators`` and
``evaluator_registry`` (batch evaluators, the backends), ``fitting`` (response surfaces of targets),
``calibrate`` (optimum through doe.optimise, confirmation, Gauss-Newton steps), ``localise``,
``attribute``, ``decisions``, ``stats``, ``standin`` and ``standin_job`` (closed-form battery with
every candidate effect) and ``testbed`` (tier-A hidden-effect cases).
"""
