"""Outcomes linked back to stored occupants, and the triage quality they measure.

- ``iss.py``: the Injury Severity Score's possible values (the ISS table has gaps);
- ``schemas.py``: the wire of an outcome (in and out);
- ``service.py``: write an outcome (idempotent, append-only history), read it;
- ``importer.py`` / ``command.py``: ``outcomes import FILE.csv``, whole file or nothing;
- ``quality.py``: under- and over-triage, calibration by decile, by month, operating
  point and tier; ``stats.py``: Wilson intervals, weighted shares;
- ``drift.py``: the drift alarm (a score test of observed against predicted ISS 15+
  over the last linked occupants) and its Prometheus collector;
- ``endpoints.py``: the thin router.
"""
