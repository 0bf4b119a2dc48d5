"""Run a CasADi step Function over a whole log in compiled C (``mapaccum`` equivalent).

CasADi generates C for the step; a short generated C loop feeds it one
sample after another and carries the accumulated outputs (the filter state)
to the next sample, like ``Function.mapaccum`` but without its per-call
copying. The shared library is built with the system C compiler once per
step Function, cached in a private per-user build folder by the hash of its
source (so it is never stale), and called through ctypes on numpy arrays.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from wheelload.models.build_folder import build_folder

COMPILER = ("gcc", "-O2", "-std=c99", "-fPIC", "-shared")

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


def _loop_source(
    step: ca.Function,
    n_accum: int,
    per_sample: tuple[int, ...],
    fixed: tuple[int, ...],
    outputs: tuple[int, ...],
) -> str:
    buffers, assign, record, finish = [], [], [], []
    for i in range(n_accum):
        size = step.nnz_out(i)
        buffers.append(f"    casadi_real acc{i}[2][{size}];")
        buffers.append(f"    memcpy(acc{i}[0], init[{i}], sizeof acc{i}[0]);")
        assign.append(f"        arg[{i}] = acc{i}[cur]; res[{i}] = acc{i}[nxt];")
        record.append(
            f"        if (history[{i}]) memcpy(history[{i}] + k * {size}, acc{i}[nxt], "
            f"sizeof acc{i}[0]);"
        )
        finish.append(f"    memcpy(final[{i}], acc{i}[n & 1], sizeof acc{i}[0]);")
    for j, i in enumerate(fixed):
        assign.append(f"        arg[{i}] = fixed[{j}];")
    for j, i in enumerate(per_sample):
        assign.append(f"        arg[{i}] = per_sample[{j}] + k * {step.nnz_in(i)};")
    for j, i in enumerate(outputs):
        assign.append(f"        res[{i}] = out[{j}] + k * {step.nnz_out(i)};")
    return LOOP.format(
        name=step.name(),
        sz_arg=step.sz_arg(),
        sz_res=step.sz_res(),
        sz_iw=step.sz_iw(),
        sz_w=step.sz_w(),
        buffers="\n".join(buffers),
        assign="\n".join(assign),
        record="\n".join(record),
        finish="\n".join(finish),
    )


def _shared_library(source: str, name: str, compiler: tuple[str, ...] = COMPILER) -> ctypes.CDLL:
    """Compile ``source`` once (cached by its hash and ``compiler``) and load it.

    A cached library that does not load (truncated, empty, corrupt) is
    removed and built again.
    """
    key = source if compiler == COMPILER else " ".join(compiler) + "\n" + source
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    folder = build_folder()
    library = folder / f"{name}_{digest}.so"
    if library.exists():
        try:
            return ctypes.CDLL(str(library))
        except OSError:
            library.unlink(missing_ok=True)
    if not library.exists():
        handle, c_name = tempfile.mkstemp(suffix=".c", prefix=f"{name}_", dir=folder)
        c_file = Path(c_name)
        with os.fdopen(handle, "w") as stream:
            stream.write(source)
        partial = c_file.with_suffix(".so.tmp")
        try:
            subprocess.run(
                [*compiler, "-o", str(partial), str(c_file), "-lm"],
                check=True,
                capture_output=True,
                text=True,
            )
        except FileNotFoundError:
            raise RuntimeError(
                "no C compiler 'gcc' found: it is needed to run the filter "
                "over a log in compiled code"
            ) from None
        except subprocess.CalledProcessError as error:
            raise RuntimeError(f"compiling {name} failed:\n{error.stderr}") from None
        finally:
            c_file.unlink(missing_ok=True)
        partial.replace(library)
    return ctypes.CDLL(str(library))


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
        self._loop = getattr(_shared_library(source, step.name()), f"{step.name()}_loop")
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
