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
  chosen on it, and the over-fit warning.

Nothing here imports the commands or the diagnosis.
"""
