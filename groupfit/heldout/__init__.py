"""Held-out validation: does a model hold on the next run?

The one home of the questions ``fit``, ``compare``, ``diagnose`` and ``sweep``
ask of a model before it goes onto the machine:

* :mod:`~groupfit.heldout.folds`: folds that imitate the next run (one operating
  condition or one run at a time);
* :mod:`~groupfit.heldout.design`: a model's regressors as its groups fit them;
* :mod:`~groupfit.heldout.scorer`: the held-out squared error of a design, and of
  the design with one more regressor;
* :mod:`~groupfit.heldout.selection`: inputs chosen on held-out folds;
* :mod:`~groupfit.heldout.check`: a model's own held-out check, the ridge penalty
  chosen on it, and the over-fit warning;
* :mod:`~groupfit.heldout.nextrun`: folds that imitate a next run (forward chaining
  over operating segments, leave-one-run-out), scored through the run-time rule;
* :mod:`~groupfit.heldout.calibration`: the factor and range learned on the
  calibration panel (``bench/bench_next_run.py``);
* :mod:`~groupfit.heldout.choice`: the one-standard-error rule;
* :mod:`~groupfit.heldout.expect`: the expected next-run error of each candidate,
  the one it chooses and the notes on when not to trust it;
* :mod:`~groupfit.heldout.reference_choice`: the default ambient reference, or none,
  by the expected next-run error;
* :mod:`~groupfit.heldout.span`: a run beyond the modelling run's inputs.

Nothing here imports the commands or the diagnosis.
"""
