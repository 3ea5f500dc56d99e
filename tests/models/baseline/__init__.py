"""Tests of the statistical baseline (models.baseline)."""
