"""One filter step in compiled C on preallocated buffers: the fast per-sample path.

:meth:`TwoStageKF.step` calls the step Function through CasADi's virtual
machine with numpy glue around it (about 200 µs). :class:`CompiledStep`
compiles the same Function's instructions as straight-line C (the emitter
of the generated library, :mod:`wheelload.estimators.kernels.c_emitter`; cached like
the whole-log loop, :mod:`wheelload.estimators.loops.compiled`) beside a small C
wrapper that sanitises the inputs (a non-finite input is invalid and read as
zero, as :meth:`TwoStageKF.reference_step` does in numpy) and computes the
:class:`StepFlag` bits, and calls it through ctypes on one preallocated
buffer: a few microseconds per sample, the same numbers as the reference
step (the same operations in the same order, without FMA contraction).

:class:`LiveFilter` (``TwoStageKF.live()``) is the leanest form: the state
stays in the buffer (copied from the step's outputs to its inputs in C) and
each update returns views into the buffer, so nothing is allocated per sample.

Example
-------
>>> fast = CompiledStep(step_function(), MAX_INTERVAL)
>>> fast.set_fixed(p, tuning)
>>> x, P, m, std, residual, flags = fast(state.x, state.P, state.m, sample.parts(), dt)
>>> live = kf.live()
>>> estimate = live.update(sample, dt)  # estimate.loads: a view, valid until the next update
"""

from __future__ import annotations

import copy
import ctypes

import casadi as ca
import numpy as np

from wheelload.estimators.kernels.c_emitter import Precision, emit_statements
from wheelload.estimators.result import StepFlag
from wheelload.models.runtime.build_folder import shared_library

#: Step inputs and outputs the wrapper expects, in the step Function's order.
INPUTS = ("x", "P", "m", "u", "u_valid", "dt", "p", "tuning")
OUTPUTS = (
    "x_next", "P_next", "m_next", "std", "residual", "used", "z", "innovation",
    "innovation_variance", "status", "fault_statistic", "fault", "mass_properties",
    "mass_properties_std",
)  # fmt: skip
#: Sizes of the input groups of ``Sample.parts()``: d, v, acc, vx, rates, rate_dots, hub.
SAMPLE_GROUPS = (4, 4, 3, 1, 3, 3, 4)

WRAPPER = """
#include <math.h>
#include <string.h>

/* buffer: inputs in order (u raw: sanitised here, u_valid written here), then the
   outputs in order, then the flags as a double. */
void {name}_fast(double *buffer)
{{
    static const unsigned long update_bits[{n_used}] = {{{update_bits}}};
    static const unsigned long guard_bits[{n_status}] = {{{guard_bits}}};
    double *u = buffer + {u_offset};
    double *valid = buffer + {valid_offset};
    const double dt = buffer[{dt_offset}];
    const double *used = buffer + {used_offset};
    const double *status = buffer + {status_offset};
    unsigned long flags = 0;
    int k;
    for (k = 0; k < {n_u}; ++k) {{
        valid[k] = isfinite(u[k]) ? 1.0 : 0.0;
        if (!isfinite(u[k])) u[k] = 0.0;
    }}
    {{
{body}
    }}
    for (k = 0; k < {n_used}; ++k) if (used[k] < 0.5) flags |= update_bits[k];
    for (k = 0; k < {n_status}; ++k) if (status[k] > 0.5) flags |= guard_bits[k];
    if (!(dt > 0.0 && dt < {max_interval!r})) flags |= {rejected}ul;
    buffer[{flags_offset}] = (double)flags;
}}

/* As {name}_fast, then x_next, P_next, m_next copied over x, P, m: the buffer
   holds the state from one sample to the next. */
void {name}_fast_carry(double *buffer)
{{
    {name}_fast(buffer);
    memcpy(buffer + {state_offset}, buffer + {next_offset}, {n_state} * sizeof(double));
}}
"""


class CompiledStep:
    """``step`` (a :func:`~wheelload.estimators.kf.step.step_function`) in compiled C.

    One buffer holds every input and output; :meth:`__call__` writes the
    state and the sample into it, calls the C step and returns views
    copied out of it. Not thread-safe (one buffer per object).
    """

    def __init__(self, step: ca.Function, max_interval: float) -> None:
        if tuple(step.name_in()) != INPUTS or tuple(step.name_out()) != OUTPUTS:
            raise ValueError(
                f"{step.name()}: expected inputs {INPUTS} and outputs {OUTPUTS}, got "
                f"{step.name_in()} and {step.name_out()}"
            )
        in_sizes = [step.nnz_in(i) for i in range(step.n_in())]
        out_sizes = [step.nnz_out(i) for i in range(step.n_out())]
        in_offsets = np.concatenate([[0], np.cumsum(in_sizes)]).astype(int)
        out_offsets = in_offsets[-1] + np.concatenate([[0], np.cumsum(out_sizes)]).astype(int)
        self.step = step
        self.buffer = np.zeros(int(out_offsets[-1]) + 1)
        self._in = {name: slice(a, b) for name, a, b in zip(INPUTS, in_offsets, in_offsets[1:])}
        self._out = {name: slice(a, b) for name, a, b in zip(OUTPUTS, out_offsets, out_offsets[1:])}
        self._flags = int(out_offsets[-1])
        n_used = out_sizes[OUTPUTS.index("used")]
        n_status = out_sizes[OUTPUTS.index("status")]
        # Emitted by wheelload's emitter: one C statement per instruction of the
        # Function's algorithm, the operations CasADi's virtual machine runs.
        body = emit_statements(
            step,
            [f"buffer[{int(k)} + {{}}]" for k in in_offsets[:-1]],
            [f"buffer[{int(k)} + {{}}]" for k in out_offsets[:-1]],
            Precision.DOUBLE,
            "double",
        )
        source = WRAPPER.format(
            name=step.name(),
            body="\n".join(f"        {line}" for line in body.splitlines()),
            n_used=n_used,
            n_status=n_status,
            update_bits=", ".join(f"{f.value}ul" for f in StepFlag.update_flags()[:n_used]),
            guard_bits=", ".join(f"{f.value}ul" for f in StepFlag.guard_flags()[:n_status]),
            n_u=in_sizes[INPUTS.index("u")],
            u_offset=self._in["u"].start,
            valid_offset=self._in["u_valid"].start,
            dt_offset=self._in["dt"].start,
            used_offset=self._out["used"].start,
            status_offset=self._out["status"].start,
            flags_offset=self._flags,
            max_interval=float(max_interval),
            rejected=StepFlag.STEP_REJECTED.value,
            state_offset=self._in["x"].start,
            next_offset=self._out["x_next"].start,
            n_state=self._in["m"].stop - self._in["x"].start,
        )
        library = shared_library(source, f"{step.name()}_fast")
        function = getattr(library, f"{step.name()}_fast")
        carry = getattr(library, f"{step.name()}_fast_carry")
        for c_function in (function, carry):
            c_function.restype = None
            c_function.argtypes = [ctypes.c_void_p]
        self._function = function
        self._carry = carry
        if not (
            self._in["x"].stop == self._in["P"].start
            and self._in["P"].stop == self._in["m"].start
            and self._in["m"].stop == self._in["u"].start
        ):
            raise RuntimeError("x, P, m and u must be adjacent in the buffer")
        self._bind(self.buffer)

    def _bind(self, buffer: np.ndarray) -> None:
        """Point the views, the C address and the result slices at ``buffer``."""
        self.buffer = buffer
        self._address = ctypes.c_void_p(buffer.ctypes.data)
        self._views = {name: buffer[where] for name, where in {**self._in, **self._out}.items()}
        self._dt = self._in["dt"].start
        self._u = self._views["u"]
        self._state_and_u = buffer[self._in["x"].start : self._in["u"].stop]
        self._state = buffer[self._in["x"].start : self._in["m"].stop]
        self._last: tuple = (None, None, None, None)  # x, P, m returned last, their block
        self._missing = {size: np.full(size, np.nan) for size in range(1, 9)}
        # The input groups of Sample.parts() as views into u (vx: one entry).
        # None if the step takes other inputs than Sample's: call_sample then uses parts().
        bounds = np.cumsum([0, *SAMPLE_GROUPS])
        self._groups = (
            tuple(self._u[a:b] for a, b in zip(bounds, bounds[1:]))
            if bounds[-1] == self._u.size
            else None
        )
        first = self._out["x_next"].start
        self._result = slice(first, self._out["residual"].stop)
        self._parts = tuple(
            slice(self._out[name].start - first, self._out[name].stop - first)
            for name in ("x_next", "P_next", "m_next", "std", "residual")
        )

    def clone(self) -> CompiledStep:
        """The same compiled step on a buffer of its own (a copy of this one's)."""
        twin = copy.copy(self)
        twin._bind(self.buffer.copy())
        return twin

    def set_fixed(self, p: np.ndarray, tuning: np.ndarray) -> None:
        """Write the parameters and the tuning (kept until the next call of this)."""
        self._views["p"][:] = p
        self._views["tuning"][:] = tuning

    def set_interval(self, index: int, value: float) -> None:
        """Set one entry of the tuning vector (the nominal interval) in place."""
        self._views["tuning"][index] = value

    def __call__(self, x, P, m, u_parts, dt: float):
        """One step from state ``(x, P, m)`` and the raw inputs (NaN = missing).

        ``u_parts``: ``(values or None, size)`` pairs in input order, values a
        sequence (e.g. ``(vx,)`` for one value); None is missing. Returns new
        arrays ``x, P (4 x 4), m, std, residual`` and the :class:`StepFlag`
        bits as an int.
        """
        last = self._last
        if x is last[0] and P is last[1] and m is last[2]:
            # The very arrays this object returned last: x, P, m lie in order at
            # the start of their block, as in the buffer: one copy.
            self._state[:] = last[3][: self._state.size]
            np.concatenate(
                [self._missing[size] if values is None else values for values, size in u_parts],
                out=self._u,
            )
        else:
            parts = [x, P.ravel(order="F"), m]
            for values, size in u_parts:
                parts.append(self._missing[size] if values is None else values)
            np.concatenate(parts, out=self._state_and_u)  # x, P, m, u are adjacent
        return self._step_and_copy(dt)

    def call_sample(self, x, P, m, sample, dt: float):
        """As :meth:`__call__` with a :class:`~wheelload.estimators.Sample` (its groups written
        straight into the buffer)."""
        if self._groups is None:
            return self(x, P, m, sample.parts(), dt)
        last = self._last
        if x is last[0] and P is last[1] and m is last[2]:
            self._state[:] = last[3][: self._state.size]  # see __call__
        else:
            views = self._views
            views["x"][:] = x
            views["P"][:] = P.ravel(order="F")
            views["m"][:] = m
        write_sample(self._groups, sample)
        return self._step_and_copy(dt)

    def _step_and_copy(self, dt: float):
        """Run the C step on the buffer; fresh copies of its results (see :meth:`__call__`)."""
        buffer = self.buffer
        buffer[self._dt] = dt
        self._function(self._address)
        # One fresh copy per step: x_next, P_next, m_next, std, residual, NaN, flags.
        block = buffer[self._result].copy()
        xs, Ps, ms, stds, residuals = self._parts
        x, P, m = block[xs], block[Ps].reshape(4, 4, order="F"), block[ms]
        self._last = (x, P, m, block)
        return x, P, m, block[stds], block[residuals], int(buffer[self._flags])


def write_sample(groups: tuple[np.ndarray, ...], sample) -> None:
    """Write a :class:`~wheelload.estimators.Sample` into the views ``groups`` of the step's
    ``u`` (:data:`SAMPLE_GROUPS`); an absent optional group is NaN (missing)."""
    d, v, acc, vx, rates, rate_dots, hub = groups
    d[:] = sample.d
    v[:] = sample.v
    acc[:] = sample.acc
    vx[0] = sample.vx
    rates[:] = np.nan if sample.rates is None else sample.rates
    rate_dots[:] = np.nan if sample.rate_dots is None else sample.rate_dots
    hub[:] = np.nan if sample.hub is None else sample.hub


class LiveEstimate:
    """One sample's estimate from :meth:`LiveFilter.update`: views, valid until the next update.

    ``loads`` (4,) [N], ``std`` (4,) [N] and ``residual`` (3,) :math:`b - A x`
    are views into the filter's buffer, overwritten by the next update
    (``.copy()`` what you keep); ``flags`` is the sample's :class:`StepFlag`
    bits as an int.
    """

    __slots__ = ("loads", "std", "residual", "flags")

    def __init__(self, loads: np.ndarray, std: np.ndarray, residual: np.ndarray) -> None:
        self.loads = loads
        self.std = std
        self.residual = residual
        self.flags = 0


class LiveFilter:
    """A filter whose state lives in the compiled step's buffer: the lean per-sample path.

    :meth:`update` writes the sample into the buffer, runs the compiled step
    (the state is carried in C from one sample to the next) and returns one
    :class:`LiveEstimate` of views: no state object, no copies, no
    allocation per sample. The numbers are those of
    :meth:`~wheelload.estimators.kf.two_stage.TwoStageKF.step` (and so of the
    CasADi ``reference_step``) to the bit.

    Example
    -------
    >>> live = kf.live()
    >>> for sample, dt in stream:
    ...     estimate = live.update(sample, dt)
    ...     publish(estimate.loads)  # a view: overwritten by the next update
    """

    __slots__ = (
        "_fast", "_carry", "_address", "_buffer", "_flags", "_dt", "_u", "_groups",
        "_interval", "_default_interval", "_estimate", "_x", "_P", "_m",
    )  # fmt: skip

    def __init__(
        self,
        fast: CompiledStep,
        x: np.ndarray,
        P: np.ndarray,
        m: np.ndarray,
        *,
        interval_index: int | None,
        default_interval: float,
        max_interval: float,
    ) -> None:
        fast = fast.clone()
        self._fast = fast
        self._carry = fast._carry
        self._address = fast._address
        self._buffer = fast.buffer
        self._flags = fast._flags
        self._dt = fast._dt
        self._u = fast._u
        views = fast._views
        self._x, self._P, self._m = views["x"], views["P"], views["m"]
        if fast._groups is None:
            raise ValueError(f"{fast.step.name()}: its inputs are not those of Sample")
        self.reset(x, P, m)
        self._groups = fast._groups
        # Without a nominal interval the measurement noise follows each valid dt.
        self._interval = (
            None
            if interval_index is None
            else fast._views["tuning"][interval_index : interval_index + 1]
        )
        self._default_interval = (default_interval, max_interval)
        self._estimate = LiveEstimate(views["x_next"], views["std"], views["residual"])

    def reset(self, x: np.ndarray, P: np.ndarray, m: np.ndarray) -> None:
        """Start again from state ``x`` [N], ``P`` (4 x 4) [N^2], fault monitor ``m``."""
        self._x[:] = x
        self._P[:] = np.ravel(P, order="F")
        self._m[:] = m
        self._fast._views["x_next"][:] = x

    def state_view(self) -> np.ndarray:
        """``x``, ``P`` (column-major) and ``m`` as one view into the buffer: what is written
        into it is the state the next update starts from."""
        return self._fast._state

    def set_fixed(self, p: np.ndarray, tuning: np.ndarray) -> None:
        """Write this filter's parameters and tuning (its own buffer's)."""
        self._fast.set_fixed(p, tuning)

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Copies of the current ``x``, ``P`` (4 x 4) and ``m``."""
        return self._x.copy(), self._P.reshape(4, 4, order="F").copy(), self._m.copy()

    def update(self, sample, dt: float) -> LiveEstimate:
        """One prediction and both updates with a :class:`~wheelload.estimators.Sample`."""
        write_sample(self._groups, sample)
        return self._run(dt)

    def update_inputs(self, u: np.ndarray, dt: float) -> LiveEstimate:
        """As :meth:`update` from the input vector ``u`` (``wheelload.models.INPUTS`` order, NaN
        missing): one copy into the buffer."""
        self._u[:] = u
        return self._run(dt)

    def _run(self, dt: float) -> LiveEstimate:
        buffer = self._buffer
        if self._interval is not None:
            default, longest = self._default_interval
            self._interval[0] = dt if 0.0 < dt < longest else default
        buffer[self._dt] = dt
        self._carry(self._address)
        estimate = self._estimate
        estimate.flags = int(buffer[self._flags])
        return estimate
