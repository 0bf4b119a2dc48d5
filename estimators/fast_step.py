"""One filter step in compiled C on preallocated buffers: the fast per-sample path.

:meth:`TwoStageKF.step` calls the step Function through CasADi's virtual
machine with numpy glue around it (about 200 µs). :class:`CompiledStep`
compiles the same Function's instructions as straight-line C (the emitter
of the generated library, :mod:`wheelload.estimators.c_emitter`; cached like
the whole-log loop, :mod:`wheelload.estimators.compiled`) beside a small C
wrapper that sanitises the inputs (a non-finite input is invalid and read as
zero, as :meth:`TwoStageKF.reference_step` does in numpy) and computes the
:class:`StepFlag` bits, and calls it through ctypes on one preallocated
buffer: a few microseconds per sample, the same numbers as the reference
step (the same operations in the same order, without FMA contraction).

Example
-------
>>> fast = CompiledStep(step_function(), MAX_INTERVAL)
>>> fast.set_fixed(p, tuning)
>>> x, P, m, std, residual, flags = fast(state.x, state.P, state.m, sample.parts(), dt)
"""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np

from wheelload.estimators.c_emitter import Precision, emit_statements
from wheelload.estimators.compiled import _shared_library
from wheelload.estimators.result import StepFlag

#: Step inputs and outputs the wrapper expects, in the step Function's order.
INPUTS = ("x", "P", "m", "u", "u_valid", "dt", "p", "tuning")
OUTPUTS = (
    "x_next", "P_next", "m_next", "std", "residual", "used", "z", "innovation",
    "innovation_variance", "status", "fault_statistic", "fault",
)  # fmt: skip

WRAPPER = """
#include <math.h>

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
"""


class CompiledStep:
    """``step`` (a :func:`~wheelload.estimators.two_stage.step_function`) in compiled C.

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
        )
        library = _shared_library(source, f"{step.name()}_fast")
        function = getattr(library, f"{step.name()}_fast")
        function.restype = None
        function.argtypes = [ctypes.c_void_p]
        self._function = function
        self._address = ctypes.c_void_p(self.buffer.ctypes.data)
        self._views = {
            name: self.buffer[where] for name, where in {**self._in, **self._out}.items()
        }
        self._dt = self._in["dt"].start
        self._u = self._views["u"]
        if (
            not self._in["x"].stop == self._in["P"].start
            and self._in["m"].stop == self._in["u"].start
        ):
            raise RuntimeError("x, P, m and u must be adjacent in the buffer")
        self._state_and_u = self.buffer[self._in["x"].start : self._in["u"].stop]
        self._state = self.buffer[self._in["x"].start : self._in["m"].stop]
        self._last: tuple = (None, None, None, None)  # x, P, m returned last, their block
        self._missing = {size: np.full(size, np.nan) for size in range(1, 9)}
        first = self._out["x_next"].start
        self._result = slice(first, self._out["residual"].stop)
        self._parts = tuple(
            slice(self._out[name].start - first, self._out[name].stop - first)
            for name in ("x_next", "P_next", "m_next", "std", "residual")
        )

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
        buffer = self.buffer
        buffer[self._dt] = dt
        self._function(self._address)
        # One fresh copy per step: x_next, P_next, m_next, std, residual, NaN, flags.
        block = buffer[self._result].copy()
        xs, Ps, ms, stds, residuals = self._parts
        x, P, m = block[xs], block[Ps].reshape(4, 4, order="F"), block[ms]
        self._last = (x, P, m, block)
        return x, P, m, block[stds], block[residuals], int(buffer[self._flags])
