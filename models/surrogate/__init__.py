"""Polynomial chaos surrogates of the occupant LPMs.

Offline, :mod:`models.offline.surrogate.build` (``aacn-triage build-surrogates``) runs
the LPMs on Latin hypercube designs and fits sparse arbitrary PCEs with 150
bootstrap replicates per output; the artifacts (npz + ``manifest.json``) live
in ``models/surrogate/artifacts``. On the request path,
:class:`models.surrogate.evaluate.SurrogateLibrary` loads and verifies them and
:meth:`~models.surrogate.evaluate.SurrogateFamily.propagate` turns the sensor
uncertainty into 95% intervals (numpy only). See ``REPORT.md`` for degrees,
LOO, held-out errors and coverage.
"""
