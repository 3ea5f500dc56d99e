"""The ``aacn-triage`` command line (:mod:`service.cli.main`)."""
