"""Run a CasADi step Function over a whole log in compiled C (``mapaccum`` equivalent).

CasADi generates C for the step; a short generated C loop feeds it one
sample after another and carries the accumulated outputs (the filter state)
to the next sample, like ``Function.mapaccum`` but without its per-call
copying. The shared library is built with the system C compiler once per
step Function, cached in a private per-user build folder by the hash of its
source (so it is never stale; a stored step's column loop by the hash of the code
that generates the source, :func:`~wheelload.models.runtime.build_folder.keyed_library`,
which spares generating it), and called through ctypes on numpy arrays.
"""

from __future__ import annotations

import ctypes
import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.models.runtime.build_folder import keyed_library, shared_library
from wheelload.models.runtime.function_cache import builder_name, stored_stem
from wheelload.models.runtime.function_library import Signature, stored_library

LOOP = """
#include <string.h>

CASADI_SYMBOL_EXPORT int {name}_loop(long n, const double** init, const double** fixed,
        const double** per_sample, double** final, double** history, double** out) {{
    const casadi_real* arg[{sz_arg}] = {{0}};
    casadi_real* res[{sz_res}] = {{0}};
    casadi_int iw[{sz_iw} + 1];
    casadi_real w[{sz_w} + 1];
{buffers}
    long k;
    for (k = 0; k < n; ++k) {{
        int cur = (int)(k & 1), nxt = 1 - cur;
{assign}
        if ({name}(arg, res, iw, w, 0)) return 1;
{record}
    }}
{finish}
    return 0;
}}
"""


def _step_fields(step: ca.Function) -> dict[str, object]:
    """The template fields of the step itself: its C name and work-vector sizes."""
    return {
        "name": step.name(),
        "sz_arg": step.sz_arg(),
        "sz_res": step.sz_res(),
        "sz_iw": step.sz_iw(),
        "sz_w": step.sz_w(),
    }


def _carried(
    step: ca.Function, n_accum: int, initial: str, final: str
) -> tuple[list[str], list[str], list[str]]:
    """C lines of the carried state: two buffers per carried output (this sample's and the
    next, swapped each sample) filled from ``initial[i]``, the step's argument and result
    pointers into them, and the copy of the last state to ``final[i]``."""
    buffers, assign, finish = [], [], []
    for i in range(n_accum):
        buffers.append(f"    casadi_real acc{i}[2][{step.nnz_out(i)}];")
        buffers.append(f"    memcpy(acc{i}[0], {initial}[{i}], sizeof acc{i}[0]);")
        assign.append(f"        arg[{i}] = acc{i}[cur]; res[{i}] = acc{i}[nxt];")
        finish.append(f"    memcpy({final}[{i}], acc{i}[n & 1], sizeof acc{i}[0]);")
    return buffers, assign, finish


def _loop_source(
    step: ca.Function,
    n_accum: int,
    per_sample: tuple[int, ...],
    fixed: tuple[int, ...],
    outputs: tuple[int, ...],
) -> str:
    buffers, assign, finish = _carried(step, n_accum, "init", "final")
    record = [
        f"        if (history[{i}]) memcpy(history[{i}] + k * {step.nnz_out(i)}, acc{i}[nxt], "
        f"sizeof acc{i}[0]);"
        for i in range(n_accum)
    ]
    for j, i in enumerate(fixed):
        assign.append(f"        arg[{i}] = fixed[{j}];")
    for j, i in enumerate(per_sample):
        assign.append(f"        arg[{i}] = per_sample[{j}] + k * {step.nnz_in(i)};")
    for j, i in enumerate(outputs):
        assign.append(f"        res[{i}] = out[{j}] + k * {step.nnz_out(i)};")
    return LOOP.format(
        **_step_fields(step),
        buffers="\n".join(buffers),
        assign="\n".join(assign),
        record="\n".join(record),
        finish="\n".join(finish),
    )


def _pointers(arrays) -> ctypes.Array:
    kind = ctypes.POINTER(ctypes.c_double)
    return (kind * max(len(arrays), 1))(
        *[kind() if a is None else a.ctypes.data_as(kind) for a in arrays]
    )


class CompiledLoop:
    """``step`` applied over ``n`` samples in C, state carried from sample to sample.

    The first ``n_accum`` inputs and outputs are accumulated (output i feeds
    input i of the next sample); inputs named in ``per_sample`` take one row
    per sample; the remaining inputs are fixed; the remaining outputs are
    returned one row per sample.
    """

    def __init__(self, step: ca.Function, n_accum: int, per_sample: tuple[str, ...]) -> None:
        names = step.name_in()
        unknown = sorted(set(per_sample) - set(names[n_accum:]))
        if unknown:
            raise ValueError(f"{step.name()} has no input named {unknown}")
        self.step = step
        self.n_accum = n_accum
        self.per_sample = tuple(i for i in range(n_accum, step.n_in()) if names[i] in per_sample)
        self.fixed = tuple(i for i in range(n_accum, step.n_in()) if names[i] not in per_sample)
        self.outputs = tuple(range(n_accum, step.n_out()))
        generator = ca.CodeGenerator(f"{step.name()}.c", {"with_header": False})
        generator.add(step)
        source = generator.dump() + _loop_source(
            step, n_accum, self.per_sample, self.fixed, self.outputs
        )
        self._loop = getattr(shared_library(source, step.name()), f"{step.name()}_loop")
        self._loop.restype = ctypes.c_int

    def __call__(self, init, fixed, per_sample, record=()):
        """Run over ``n`` samples.

        ``init``: initial accumulated inputs; ``fixed``: the fixed inputs;
        ``per_sample``: arrays of shape (n, nnz); ``record``: indices of
        accumulated outputs whose value after every sample is returned.
        Returns ``(final, history, outputs)``.
        """
        step = self.step
        init = [np.ascontiguousarray(a, float).ravel(order="F") for a in init]
        fixed = [np.ascontiguousarray(a, float).ravel(order="F") for a in fixed]
        per_sample = [np.ascontiguousarray(a, float) for a in per_sample]
        n = per_sample[0].shape[0]
        for array, i in zip(per_sample, self.per_sample):
            if array.shape != (n, step.nnz_in(i)):
                raise ValueError(
                    f"input '{step.name_in(i)}' must have shape ({n}, {step.nnz_in(i)}), "
                    f"got {array.shape}"
                )
        for array, i in zip([*init, *fixed], [*range(self.n_accum), *self.fixed]):
            if array.size != step.nnz_in(i):
                raise ValueError(f"input '{step.name_in(i)}' must have {step.nnz_in(i)} values")
        final = [np.empty(step.nnz_out(i)) for i in range(self.n_accum)]
        history = [
            np.empty((n, step.nnz_out(i))) if i in record else None for i in range(self.n_accum)
        ]
        outputs = [np.empty((n, step.nnz_out(i))) for i in self.outputs]
        status = self._loop(
            ctypes.c_long(n),
            _pointers(init),
            _pointers(fixed),
            _pointers(per_sample),
            _pointers(final),
            _pointers(history),
            _pointers(outputs),
        )
        if status:
            raise RuntimeError(f"{step.name()} failed in the compiled loop")
        return final, history, outputs


COLUMN_LOOP = """
#include <math.h>
#include <stdint.h>
#include <string.h>

CASADI_SYMBOL_EXPORT int {name}_columns(long n, double** state, const double** fixed,
        const double** values, const long* strides, const double* t, double dt_first,
        double** columns, uint32_t* flags, uint32_t base_flags) {{
    const casadi_real* arg[{sz_arg}] = {{0}};
    casadi_real* res[{sz_res}] = {{0}};
    casadi_int iw[{sz_iw} + 1];
    casadi_real w[{sz_w} + 1];
    casadi_real u[{n_values}], valid[{n_values}], dt;
{buffers}
    long k;
    int i;
    for (k = 0; k < n; ++k) {{
        int cur = (int)(k & 1), nxt = 1 - cur;
        for (i = 0; i < {n_values}; ++i) {{
            double x = values[i] ? values[i][k * strides[i]] : NAN;
            int ok = isfinite(x);
            valid[i] = ok ? 1.0 : 0.0;
            u[i] = ok ? x : 0.0;
        }}
        dt = k ? t[k] - t[k - 1] : dt_first;
{assign}
        if ({name}(arg, res, iw, w, 0)) return 1;
{record}
        {{
            uint32_t f = base_flags;
{rules}
            flags[k] = f;
        }}
    }}
{finish}
    return 0;
}}
"""


@dataclass(frozen=True, kw_only=True)
class FlagRule:
    """Status bit ``bit`` set where element ``element`` of output ``output`` is below 0.5
    (``below``) or above it."""

    output: str
    element: int
    below: bool
    bit: int


def _column_source(step: ca.Function, layout: ColumnLayout) -> str:
    """CasADi's C of ``step`` and the column loop around it (:data:`COLUMN_LOOP`)."""
    n_accum = layout.n_accum
    generator = ca.CodeGenerator(f"{step.name()}.c", {"with_header": False})
    generator.add(step)
    names_in, names_out = step.name_in(), step.name_out()
    values, validity, interval = (names_in.index(name) for name in layout.inputs())
    fixed = layout.fixed(names_in)
    columns = tuple(names_out.index(name) for name in layout.columns)
    buffers, assign, finish = _carried(step, n_accum, "state", "state")
    record = []
    wanted = set(columns) | {names_out.index(rule.output) for rule in layout.rules}
    for i in sorted(wanted - set(range(n_accum))):
        buffers.append(f"    casadi_real out{i}[{step.nnz_out(i)}];")
        assign.append(f"        res[{i}] = out{i};")
    for j, i in enumerate(fixed):
        assign.append(f"        arg[{i}] = fixed[{j}];")
    assign.append(f"        arg[{values}] = u; arg[{validity}] = valid; arg[{interval}] = &dt;")
    column = 0
    for i in columns:
        source = f"acc{i}[nxt]" if i < n_accum else f"out{i}"
        for e in range(step.nnz_out(i)):
            record.append(f"        if (columns[{column}]) columns[{column}][k] = {source}[{e}];")
            column += 1
    lines = []
    for rule in layout.rules:
        i = names_out.index(rule.output)
        source = f"acc{i}[nxt]" if i < n_accum else f"out{i}"
        test = "<" if rule.below else ">"
        lines.append(
            f"            if ({source}[{rule.element}] {test} 0.5) f |= (uint32_t){rule.bit}u;"
        )
    return generator.dump() + COLUMN_LOOP.format(
        **_step_fields(step),
        n_values=step.nnz_in(values),
        buffers="\n".join(buffers),
        assign="\n".join(assign),
        record="\n".join(record),
        rules="\n".join(lines),
        finish="\n".join(finish),
    )


@dataclass(frozen=True, kw_only=True)
class ColumnLayout:
    """What a :class:`ColumnLoop` feeds the step and takes from it: the first ``n_accum``
    inputs and outputs carried, the per-sample inputs ``values``, ``validity``,
    ``interval``, the output ``columns`` and the status bits' ``rules``."""

    n_accum: int
    values: str
    validity: str
    interval: str
    columns: tuple[str, ...]
    rules: tuple[FlagRule, ...]

    def inputs(self) -> tuple[str, str, str]:
        return (self.values, self.validity, self.interval)

    def fixed(self, names_in) -> tuple[int, ...]:
        """The fixed inputs: neither carried nor per sample."""
        return tuple(i for i in range(self.n_accum, len(names_in))
                     if names_in[i] not in self.inputs())  # fmt: skip


class ColumnLoop:
    """``step`` over a log's column arrays in C: validity, interval and status bits computed there.

    The lean whole-log path: the per-sample input ``values`` is gathered from
    one (strided) column array per element (``None``: a missing channel), its
    validity is ``isfinite`` and a non-finite value enters as 0 (as
    ``np.nan_to_num``); ``interval`` is ``t[k] - t[k-1]`` (``dt_first`` for the
    first sample of a call, so a long log runs in chunks with the state carried
    in place); each element of the outputs named in ``columns`` is written to
    its own column array; each :class:`FlagRule` sets a bit of the ``uint32``
    status. The arithmetic is the step's own generated C, as in
    :class:`CompiledLoop`, so both give the same numbers to the bit.
    :class:`ColumnLayout` names the inputs and outputs; :meth:`stored` gives the loop of a
    stored step without CasADi once built.
    """

    def __init__(self, step: ca.Function, layout: ColumnLayout) -> None:
        self._set_up(Signature.of(step), layout)
        name = f"{step.name()}_columns"
        stem = stored_stem(step)
        if stem is None:
            library = shared_library(_column_source(step, layout), name)
        else:  # a stored step: the code determines it, and with the layout the source
            source = functools.partial(_column_source, step, layout)
            library = keyed_library(f"{stem} {name} {layout!r}", source, name)
        self._bind(library)

    @classmethod
    def stored(cls, builder, layout: ColumnLayout) -> ColumnLoop:
        """The loop of ``builder()``'s stored step
        (:func:`~wheelload.models.runtime.function_cache.stored_function`): its signature and
        library read without CasADi when this code built them before
        (:func:`~wheelload.models.runtime.function_library.stored_library`)."""
        loop = cls.__new__(cls)
        source = functools.partial(_column_source, layout=layout)
        name = f"{builder_name(builder)[1]}_columns"
        signature, library = stored_library(builder, name, f"columns {layout!r}", source)
        loop._set_up(signature, layout)
        loop._bind(library)
        return loop

    def _set_up(self, signature: Signature, layout: ColumnLayout) -> None:
        """Check ``layout`` against the step's ``signature`` and keep the sizes it gives."""
        names_in, names_out, name = signature.names_in, signature.names_out, signature.name
        n_accum = layout.n_accum
        for input_name in layout.inputs():
            if input_name not in names_in[n_accum:]:
                raise ValueError(f"{name} has no per-sample input named '{input_name}'")
        for output in (*layout.columns, *(rule.output for rule in layout.rules)):
            if output not in names_out:
                raise ValueError(f"{name} has no output named '{output}'")
        for rule in layout.rules:
            if not 0 <= rule.element < signature.nnz_out[names_out.index(rule.output)]:
                raise ValueError(f"{name}: output '{rule.output}' has no element {rule.element}")
        inputs = tuple(names_in.index(i) for i in layout.inputs())
        nnz_in = signature.nnz_in
        if nnz_in[inputs[1]] != nnz_in[inputs[0]] or nnz_in[inputs[2]] != 1:
            raise ValueError(
                f"{name}: '{layout.validity}' must match '{layout.values}', "
                f"'{layout.interval}' be 1"
            )
        self.signature = signature
        self.n_accum = n_accum
        self.n_values = nnz_in[inputs[0]]
        self.fixed = layout.fixed(names_in)
        self.columns = tuple(names_out.index(c) for c in layout.columns)
        self.n_columns = sum(signature.nnz_out[i] for i in self.columns)

    def _bind(self, library: ctypes.CDLL) -> None:
        self._loop = getattr(library, f"{self.signature.name}_columns")
        self._loop.restype = ctypes.c_int

    def __call__(
        self,
        state: list[np.ndarray],
        fixed: list[np.ndarray],
        values: list[np.ndarray | None],
        t: np.ndarray,
        dt_first: float,
        columns: list[np.ndarray | None],
        flags: np.ndarray,
        base_flags: int = 0,
    ) -> None:
        """Run over ``len(t)`` samples; ``state`` (float arrays) is updated in place.

        ``values``: one 1-D float64 array per element of the per-sample input
        (any stride) or ``None``; ``columns``: one contiguous float64 array of
        ``len(t)`` per output element, or ``None`` to leave it out; ``flags``:
        contiguous ``uint32`` of ``len(t)``.
        """
        signature = self.signature
        n = len(t)
        t = np.ascontiguousarray(t, dtype=np.float64)
        if len(state) != self.n_accum or any(
            a.dtype != np.float64 or not a.flags.c_contiguous or a.size != signature.nnz_out[i]
            for i, a in enumerate(state)
        ):
            raise ValueError(
                f"{signature.name}: state must be {self.n_accum} contiguous float arrays"
            )
        fixed = [np.ascontiguousarray(a, float).ravel(order="F") for a in fixed]
        for array, i in zip(fixed, self.fixed, strict=True):
            if array.size != signature.nnz_in[i]:
                raise ValueError(
                    f"input '{signature.names_in[i]}' must have {signature.nnz_in[i]} values"
                )
        if len(values) != self.n_values or len(columns) != self.n_columns:
            raise ValueError(
                f"{signature.name}: give {self.n_values} value and {self.n_columns} output columns"
            )
        strides = np.zeros(self.n_values, dtype=np.int64)
        for j, array in enumerate(values):
            if array is None:
                continue
            if array.dtype != np.float64 or array.ndim != 1 or array.shape[0] != n:
                raise ValueError(f"value column {j} must be float64 of {n} samples")
            if array.strides[0] % 8:
                raise ValueError(f"value column {j} is not aligned to its elements")
            strides[j] = array.strides[0] // 8
        for array in columns:
            if array is not None and (
                array.dtype != np.float64 or not array.flags.c_contiguous or array.shape[0] < n
            ):
                raise ValueError(f"output columns must be contiguous float64 of {n} samples")
        if flags.dtype != np.uint32 or not flags.flags.c_contiguous or flags.shape[0] < n:
            raise ValueError(f"flags must be contiguous uint32 of {n} samples")
        status = self._loop(
            ctypes.c_long(n),
            _pointers(state),
            _pointers(fixed),
            _pointers(values),
            strides.ctypes.data_as(ctypes.POINTER(ctypes.c_long)),
            t.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            ctypes.c_double(dt_first),
            _pointers(columns),
            flags.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)),
            ctypes.c_uint32(base_flags),
        )
        if status:
            raise RuntimeError(f"{signature.name} failed in the compiled loop")
