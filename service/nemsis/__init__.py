"""NEMSIS v3.5.1: every stored case as an EMS patient care record.

- ``codes``: the NEMSIS code lists used and the element template of a report.
- ``mapping``: a stored case -> an ``EMSDataSet`` document and its report.
- ``veds_source``: what a VEDS case's own document adds (every pulse, empty seats).
- ``validate``: validation against the shipped XSDs (``xsd/``, with their provenance).
- ``service``: who may read which case's record; build and validate (the use case).
- ``endpoints``: ``GET /v1/cases/{case_id}/nemsis``.
- ``export``: many cases to a directory (the command, ``aacn-triage cases export --nemsis``,
  is ``service.cli.export``).
"""
