"""One module per command-line verb; :mod:`groupfit.cli` parses and dispatches."""
