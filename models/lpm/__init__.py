"""Occupant engine: four 2-D lumped parameter models.

Public API: :func:`models.lpm.simulate.simulate`, :class:`models.lpm.simulate.LpmResult`,
:func:`models.lpm.simulate.warm_up`, :func:`models.lpm.params.load_parameter_set`,
:func:`models.lpm.params.available_parameter_sets`.
"""
