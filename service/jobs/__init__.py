"""Batch and recall work of the command line; never imported by the request path."""
