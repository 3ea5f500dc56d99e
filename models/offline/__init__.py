"""Offline tools: fits, builds, validations, reports, plots and research checks.

They import the engine (``models``); the engine and the service's request path
never import them. Their heavy dependencies (matplotlib, scikit-learn,
statsmodels, chaospy) come with the ``offline`` extra
(``pip install 'aacn-triage[offline]'``). Their reports and figures go under the
repository's ``docs/`` (or the tool's ``--out``), never into the installed
package; the artifacts they build (surrogates, fitted models) go where the
engine loads them from.
"""
