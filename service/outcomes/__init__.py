"""Outcomes linked back to stored occupants, and the triage quality they measure.

- ``iss.py``: the Injury Severity Score's possible values (the ISS table has gaps);
- ``schemas.py``: the wire of an outcome (in and out);
- ``service.py``: write an outcome (idempotent, append-only history), read it;
- ``importer.py``: ``outcomes import FILE.csv``, whole file or nothing;
- ``quality.py``: under- and over-triage, calibration by decile, by month, operating
  point and tier; ``stats.py``: Wilson intervals, weighted shares;
- ``drift.py``: the drift alarm (a score test of observed against predicted ISS 15+
  over the last linked occupants) and its Prometheus collector;
- ``recalibrate.py``: ``outcomes recalibrate``, the linked outcomes read, the new version
  written;
- ``endpoints.py``: the thin router;
- ``page_endpoints.py``: the quality page (HTML), its view ``quality_page.py`` and
  reliability plot ``reliability.py``, its template ``templates/quality.html``, in the
  pages' frame (``service.page_frame``).
"""
