"""The ``/v1/cases`` request path: wire in, the engine, the store, wire out."""
