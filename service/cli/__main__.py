"""``python -m service.cli``: the ``aacn-triage`` command line (:mod:`service.cli.main`)."""

from service.cli.main import main

raise SystemExit(main())
