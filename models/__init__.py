"""aacn-triage engine: pulses, occupant models, injury scores, surrogates, baseline.

Plain data in, plain data out. Nothing in this package imports the web layer
(`service`), FastAPI or SQLAlchemy.
"""

#: Version of the engine code. Stored with every case; bump on any change that
#: can alter a result.
ENGINE_VERSION = "0.2.0"
