"""Channel frequency class (CFC) filtering, SAE J211-1 Appendix C / ISO 6487.

The CFC filter is a 2-pole Butterworth-like low-pass recursion run forward and
then backward over the data (phaseless, 4-pole overall). Reference:
``injury-criteria.md`` section 4 (weisang.com FlexPro documentation, dynasaur
``cfc.py``, pyisomme ``channel.py``) [S].

The recursion, with sample period ``T`` in s::

    Y[t] = a0 X[t] + a1 X[t-1] + a2 X[t-2] + b1 Y[t-1] + b2 Y[t-2]
    wd = 2 pi CFC 2.0775                 (SAE J211; ISO 6487 uses 2.0833)
    wa = tan(wd T / 2)
    a0 = wa^2 / (1 + sqrt(2) wa + wa^2);  a1 = 2 a0;  a2 = a0
    b1 = -2 (wa^2 - 1) / (1 + sqrt(2) wa + wa^2)
    b2 = (-1 + sqrt(2) wa - wa^2) / (1 + sqrt(2) wa + wa^2)

Channel classes commonly used (J211 table, reference section 4): head
acceleration CFC 1000, neck channels for Nij CFC 600, spine acceleration 180,
thorax deflection 180 (FMVSS/NCAP practice) or 600 (J211 table), vehicle crash
pulse 60.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Final, Literal

import numpy as np
import numpy.typing as npt
from numba import njit

__all__ = [
    "CFC_CLASSES",
    "ISO_6487_DESIGN_FACTOR",
    "PAD_DURATION_S",
    "SAE_J211_DESIGN_FACTOR",
    "cfc_coefficients",
    "cfc_filter",
    "cfc_filter_rows",
    "forward_backward",
]

#: Channel frequency classes accepted by :func:`cfc_filter`.
CFC_CLASSES: Final[frozenset[int]] = frozenset({60, 180, 600, 1000})

#: Design-frequency factor of SAE J211-1 Appendix C: wd = 2 pi CFC 2.0775.
#: [S] reference section 4 (FlexPro documentation, dynasaur, pyisomme).
SAE_J211_DESIGN_FACTOR: Final[float] = 2.0775

#: Design-frequency factor of ISO 6487: 1.25 * 5/3 = 2.0833...
#: [S] reference section 4.
ISO_6487_DESIGN_FACTOR: Final[float] = 1.25 * 5.0 / 3.0

#: Minimum duration of the end padding, s. [R] dynasaur mirrors about 10 ms at
#: each end (reference section 4); J211 asks for pre-event data or start-up
#: padding without fixing a length.
PAD_DURATION_S: Final[float] = 0.010

#: Minimum padding expressed in design periods: the pad is at least this many
#: periods of the design frequency ``CFC * factor``, so that the start-up
#: transient of the low classes (CFC 60) has died out before the data. [R]
_PAD_DESIGN_PERIODS: Final[float] = 4.0

_SQRT2: Final[float] = math.sqrt(2.0)


def _design_factor(standard: str) -> float:
    if standard == "sae_j211":
        return SAE_J211_DESIGN_FACTOR
    if standard == "iso_6487":
        return ISO_6487_DESIGN_FACTOR
    raise ValueError("`standard` must be 'sae_j211' or 'iso_6487'.")


def _validate_rate_and_class(sample_rate_hz: float, cfc: int, factor: float) -> None:
    if not (isinstance(sample_rate_hz, int | float) and math.isfinite(sample_rate_hz)):
        raise ValueError("`sample_rate_hz` must be a finite number.")
    if sample_rate_hz <= 0.0:
        raise ValueError("`sample_rate_hz` must be positive.")
    if cfc not in CFC_CLASSES:
        raise ValueError(f"`cfc` must be one of {sorted(CFC_CLASSES)}, got {cfc!r}.")
    # tan(wd T / 2) must stay finite and positive: design frequency below Nyquist.
    if 2.0 * math.pi * cfc * factor / sample_rate_hz >= math.pi:
        raise ValueError(
            f"`sample_rate_hz` = {sample_rate_hz} Hz is too low for CFC {cfc}: the design "
            f"frequency {cfc * factor:.1f} Hz must be below the Nyquist frequency."
        )


@lru_cache(maxsize=64)
def cfc_coefficients(
    sample_rate_hz: float, cfc: int, *, standard: Literal["sae_j211", "iso_6487"] = "sae_j211"
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Coefficients of one pass of the CFC filter.

    Parameters
    ----------
    sample_rate_hz : float
        Sampling rate, Hz.
    cfc : int
        Channel frequency class: 60, 180, 600 or 1000.
    standard : {"sae_j211", "iso_6487"}, optional
        Which design factor to use (2.0775 or 2.0833). Default SAE J211.

    Returns
    -------
    b : tuple of float, length 3
        Numerator ``(a0, a1, a2)`` in the J211 notation.
    a : tuple of float, length 3
        Denominator ``(1, -b1, -b2)`` in scipy's ``lfilter`` convention.
    """
    factor = _design_factor(standard)
    _validate_rate_and_class(sample_rate_hz, cfc, factor)
    wd = 2.0 * math.pi * cfc * factor
    t = 1.0 / sample_rate_hz
    wa = math.sin(wd * t / 2.0) / math.cos(wd * t / 2.0)
    den = 1.0 + _SQRT2 * wa + wa * wa
    a0 = wa * wa / den
    b1 = -2.0 * (wa * wa - 1.0) / den
    b2 = (-1.0 + _SQRT2 * wa - wa * wa) / den
    return (a0, 2.0 * a0, a0), (1.0, -b1, -b2)


@lru_cache(maxsize=64)
def _steady_state(
    b: tuple[float, float, float], a: tuple[float, float, float]
) -> npt.NDArray[np.float64]:
    """The state of the recursion at rest after a unit step (read-only), shape (2,).

    ``scipy.signal.lfilter_zi(b, a)`` for three coefficients with ``a[0] == 1``,
    the same operations: ``(I - C^T) zi = b[1:] - a[1:] b[0]`` with ``C`` the
    companion matrix of ``a``, solved by LAPACK (tests/models/injury/
    test_injury_filters.py holds it equal, bit for bit). Written out because
    importing ``scipy.signal`` took 0.45 s of every process start (measured
    2026-12-04), for this one small system; solved once per coefficient set.
    """
    a1, a2 = float(a[1]), float(a[2])
    i_minus_ct = np.array([[1.0 - (-a1), 0.0 - 1.0], [0.0 - (-a2), 1.0 - 0.0]])
    rhs = np.array([b[1] - a1 * b[0], b[2] - a2 * b[0]], dtype=np.float64)
    zi = np.asarray(np.linalg.solve(i_minus_ct, rhs), dtype=np.float64)
    zi.flags.writeable = False
    return zi


@njit(cache=True, nogil=True)
def _forward_backward_rows(
    b: npt.NDArray[np.float64],
    a: npt.NDArray[np.float64],
    zi: npt.NDArray[np.float64],
    x: npt.NDArray[np.float64],
) -> npt.NDArray[np.float64]:
    """Each row of `x` through the 2-pole recursion forward, then backward.

    The operations, in their order, of scipy's ``lfilter`` for three coefficients
    (transposed direct form II, scipy/signal/_lfilter.c ``DOUBLE_filt``):
    ``y = z0 + b0 x; z0 = z1 + x b1 - y a1; z1 = x b2 - y a2``, each pass started
    from ``zi`` times its first sample, as ``filtfilt`` does. Compiled without
    fast-math, so no multiply-add is fused: the same bits as scipy's
    (tests/models/injury/test_injury_filters.py), in under half the time.
    """
    out = x.copy()
    _forward_backward_in_place(out, b, a, zi)
    return out


@njit(cache=True, nogil=True, inline="always")
def _forward_backward_in_place(
    y: npt.NDArray[np.float64],
    b: npt.NDArray[np.float64],
    a: npt.NDArray[np.float64],
    zi: npt.NDArray[np.float64],
) -> None:
    """Each row of `y` (shape (m, n)) through the forward, then the backward pass, in place.

    Each pass reads a sample before it writes its result there, so the numbers
    are those of passing from a copy.
    """
    m, n = y.shape
    if m == 1:
        _one_pass(y[0], b, a, zi, 0, n, 1)  # forward
        _one_pass(y[0], b, a, zi, n - 1, -1, -1)  # backward
        return
    # several rows side by side: each row's recursion is a chain of dependent
    # operations, so stepping all rows at once lets their chains overlap in the
    # processor. [R] 87 -> 42 us for four rows of 4,400 samples (measured
    # 2026-12-04); each row's operations and their order are unchanged
    z = np.empty((2, m))
    _rows_pass(y, b, a, zi, z, 0, n, 1)  # forward
    _rows_pass(y, b, a, zi, z, n - 1, -1, -1)  # backward


@njit(cache=True, nogil=True, inline="always")
def _one_pass(
    y: npt.NDArray[np.float64],
    b: npt.NDArray[np.float64],
    a: npt.NDArray[np.float64],
    zi: npt.NDArray[np.float64],
    start: int,
    stop: int,
    step: int,
) -> None:
    """One pass of the recursion over ``y[start:stop:step]``, in place."""
    x0 = y[start]
    z0 = zi[0] * x0
    z1 = zi[1] * x0
    for k in range(start, stop, step):
        xn = y[k]
        yn = z0 + b[0] * xn
        z0 = z1 + xn * b[1] - yn * a[1]
        z1 = xn * b[2] - yn * a[2]
        y[k] = yn


@njit(cache=True, nogil=True, inline="always")
def _rows_pass(
    y: npt.NDArray[np.float64],
    b: npt.NDArray[np.float64],
    a: npt.NDArray[np.float64],
    zi: npt.NDArray[np.float64],
    z: npt.NDArray[np.float64],
    start: int,
    stop: int,
    step: int,
) -> None:
    """:func:`_one_pass` of every row of `y` at once, in place.

    `z` (shape (2, rows)) is the workspace of the rows' two recursion states.
    """
    m = y.shape[0]
    for r in range(m):
        z[0, r] = zi[0] * y[r, start]
        z[1, r] = zi[1] * y[r, start]
    for k in range(start, stop, step):
        for r in range(m):
            xn = y[r, k]
            yn = z[0, r] + b[0] * xn
            z[0, r] = z[1, r] + xn * b[1] - yn * a[1]
            z[1, r] = xn * b[2] - yn * a[2]
            y[r, k] = yn


def forward_backward(
    b: tuple[float, float, float],
    a: tuple[float, float, float],
    x: npt.NDArray[np.float64],
    axis: int = -1,
) -> npt.NDArray[np.float64]:
    """The recursion run forward then backward along `axis`, no padding.

    The numbers of ``scipy.signal.filtfilt(b, a, x, axis=axis, padlen=0)`` (its
    ``method="pad"`` path: each pass started from the steady state of a step at
    its first sample), bit for bit (tests/models/injury/test_injury_filters.py):
    the steady state is solved once per coefficient set (:func:`_steady_state`)
    and the passes are a compiled loop (:func:`_forward_backward_rows`).

    Parameters
    ----------
    b, a : tuple of float, length 3
        :func:`cfc_coefficients` (``a[0] == 1``).
    x : ndarray
        Signal(s), already padded (at least one sample along `axis`).
    axis : int, optional

    Returns
    -------
    ndarray, same shape as `x`
    """
    if len(b) != 3 or len(a) != 3 or a[0] != 1.0:
        raise ValueError("forward_backward takes the three coefficients of cfc_coefficients")
    zi = _steady_state(b, a)
    moved = np.moveaxis(np.asarray(x, dtype=np.float64), axis, -1)
    rows = np.ascontiguousarray(moved.reshape(-1, moved.shape[-1]))
    y = _forward_backward_rows(np.array(b), np.array(a), np.asarray(zi), rows)
    return np.moveaxis(y.reshape(moved.shape), -1, axis)


@njit(cache=True, nogil=True)
def _padded_forward_backward_rows(
    x: npt.NDArray[np.float64],
    b: npt.NDArray[np.float64],
    a: npt.NDArray[np.float64],
    zi: npt.NDArray[np.float64],
    width: int,
) -> npt.NDArray[np.float64]:
    """Each row of `x` padded by `width` samples at both ends, filtered, cropped back.

    The padding is a point-symmetric (odd) reflection about each end, then a
    constant extension: odd reflection keeps the value and slope continuous at
    the ends, so a constant or linear signal passes unchanged; when `width`
    exceeds the data, the reflection covers ``n - 1`` samples and the rest
    repeats its end value. The padded values are the numpy expressions'
    (``2 x[0] - x[k]``, the same two operations), the passes
    :func:`_forward_backward_in_place`, and the result the central `n` samples:
    the numbers of padding with numpy and calling :func:`forward_backward`, bit
    for bit, without the padded copies and the crop's copy. [R] three rows of
    2,001 samples, CFC 180 at 10 kHz, through :func:`cfc_filter_rows`: 46 -> 28 us
    (measured 2026-12-05).

    Parameters
    ----------
    x : ndarray, shape (m, n)
        ``n >= 2``.
    b, a, zi : ndarray, shape (3,), (3,), (2,)
        Coefficients and the steady state of :func:`_steady_state`.
    width : int
        Padding at each end, >= 1.

    Returns
    -------
    ndarray, shape (m, n)
    """
    m, n = x.shape
    refl = min(width, n - 1)
    rest = width - refl
    total = n + 2 * width
    buf = np.empty((m, total))
    for r in range(m):
        twice_first = 2.0 * x[r, 0]
        twice_last = 2.0 * x[r, n - 1]
        head0 = twice_first - x[r, refl]
        for i in range(rest):
            buf[r, i] = head0
        for i in range(refl):
            buf[r, rest + i] = twice_first - x[r, refl - i]
        for i in range(n):
            buf[r, width + i] = x[r, i]
        for i in range(refl):
            buf[r, width + n + i] = twice_last - x[r, n - 2 - i]
        tail_end = twice_last - x[r, n - 1 - refl]
        for i in range(rest):
            buf[r, width + n + refl + i] = tail_end
    _forward_backward_in_place(buf, b, a, zi)
    out = np.empty((m, n))
    for r in range(m):
        for i in range(n):
            out[r, i] = buf[r, width + i]
    return out


@lru_cache(maxsize=64)
def _filter_arrays(
    sample_rate_hz: float, cfc: int, standard: Literal["sae_j211", "iso_6487"]
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64], int]:
    """The coefficients, steady state and end padding (samples) of one rate and class."""
    b, a = cfc_coefficients(sample_rate_hz, cfc, standard=standard)
    factor = _design_factor(standard)
    pad_s = max(PAD_DURATION_S, _PAD_DESIGN_PERIODS / (cfc * factor))
    width = max(1, math.ceil(pad_s * sample_rate_hz))
    arrays = (np.array(b), np.array(a), np.array(_steady_state(b, a)))
    for arr in arrays:
        arr.flags.writeable = False
    return arrays[0], arrays[1], arrays[2], width


def cfc_filter_rows(
    signals: npt.ArrayLike,
    sample_rate_hz: float,
    cfc: int,
    *,
    standard: Literal["sae_j211", "iso_6487"] = "sae_j211",
) -> npt.NDArray[np.float64]:
    """:func:`cfc_filter` of each row of `signals`: the same numbers, in one call.

    Parameters
    ----------
    signals : array_like, shape (m, n)
        Channels of one sampling rate and class, ``n >= 1``; finite.
    sample_rate_hz, cfc, standard
        As for :func:`cfc_filter`.

    Returns
    -------
    ndarray of float64, shape (m, n)

    Raises
    ------
    ValueError
        As :func:`cfc_filter` (`signals` must be 2-D here).
    """
    x = np.ascontiguousarray(signals, dtype=np.float64)
    if x.ndim != 2:
        raise ValueError(f"`signals` must be 2-D, got shape {x.shape}.")
    if x.shape[1] == 0:
        raise ValueError("`signal` must not be empty.")
    if not np.all(np.isfinite(x)):
        raise ValueError("`signal` must be finite (no NaN or inf).")
    b, a, zi, width = _filter_arrays(sample_rate_hz, cfc, standard)
    if x.shape[1] == 1:
        return x.copy()
    return _padded_forward_backward_rows(x, b, a, zi, width)


def cfc_filter(
    signal: npt.ArrayLike,
    sample_rate_hz: float,
    cfc: int,
    *,
    standard: Literal["sae_j211", "iso_6487"] = "sae_j211",
) -> npt.NDArray[np.float64]:
    """Filter a channel with the SAE J211 / ISO 6487 CFC filter.

    The J211 2-pole recursion is run forward and then backward (zero phase).
    Both ends are padded by point-symmetric reflection over
    ``max(PAD_DURATION_S, 4 / (CFC * factor))`` seconds (at least 10 ms; 32 ms
    for CFC 60) and the recursion starts in its steady state for the first
    padded value, so a constant signal is returned unchanged (unit DC gain).

    The forward-backward magnitude response is ``|H(f)|**2`` of one pass; its
    -3 dB point is close to ``1.667 * CFC`` when the sampling rate is high
    against the class (about 10x the design frequency or more, which J211
    recommends).

    Parameters
    ----------
    signal : array_like, shape (n,)
        Samples of one channel, any unit; ``n >= 1``. Must be finite.
    sample_rate_hz : float
        Sampling rate, Hz. The design frequency ``CFC * factor`` must be below
        the Nyquist frequency.
    cfc : int
        Channel frequency class: 60, 180, 600 or 1000.
    standard : {"sae_j211", "iso_6487"}, optional
        Design factor 2.0775 (SAE J211, default) or 2.0833 (ISO 6487).

    Returns
    -------
    ndarray of float64, shape (n,)
        The filtered channel, same unit as `signal`.

    Raises
    ------
    ValueError
        If `signal` is not 1-D, empty or not finite, if `sample_rate_hz` is not
        positive or too low for the class, or if `cfc` is not a CFC class.

    Examples
    --------
    >>> import numpy as np
    >>> y = cfc_filter(np.ones(100), 10_000.0, 1000)
    >>> bool(np.allclose(y, 1.0))
    True
    """
    x = np.asarray(signal, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"`signal` must be 1-D, got shape {x.shape}.")
    return cfc_filter_rows(x[None, :], sample_rate_hz, cfc, standard=standard)[0]
