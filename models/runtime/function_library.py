"""Stored model Functions as compiled C, evaluated through ctypes: no CasADi once built.

A Function of :func:`~wheelload.models.runtime.function_cache.stored_function` is
emitted as C by CasADi (its outputs made dense) with a loop that evaluates it on
``n`` samples, compiled once into the build folder
(:func:`~wheelload.models.runtime.build_folder.keyed_library`, named by the builder
and the code digest), beside its :class:`Signature` (names and sizes, JSON). A
later run reads both without importing CasADi: a warm single-log estimate takes
the models' numbers (the derived parameters, the checks' pseudo-measurements and
equilibrium rows) from this C, which performs the operations of CasADi's virtual
machine in the same order (C99, no contraction), so the numbers are the same.

Example
-------
>>> z = compiled_function(suspension_function)
>>> z.map(u, gates, p)[0]  # (4, n): as suspension_function().map(n)(u, gates, p)
"""

from __future__ import annotations

import ctypes
import functools
import json
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from wheelload.models.runtime.build_folder import build_folder, keyed_library
from wheelload.models.runtime.function_cache import (
    builder_name,
    builder_stem,
    store_text,
    stored_function,
)

MAP = """
static const long {name}_nnz_out[{n_out}] = {{{nnz_out}}};

CASADI_SYMBOL_EXPORT int {name}_map(long n, const double** in, const long* stride,
        double** out) {{
    const casadi_real* arg[{sz_arg}] = {{0}};
    casadi_real* res[{sz_res}] = {{0}};
    casadi_int iw[{sz_iw} + 1];
    casadi_real w[{sz_w} + 1];
    long k;
    int i;
    for (k = 0; k < n; ++k) {{
        for (i = 0; i < {n_in}; ++i) arg[i] = in[i] + k * stride[i];
        for (i = 0; i < {n_out}; ++i) res[i] = out[i] + k * {name}_nnz_out[i];
        if ({name}(arg, res, iw, w, 0)) return 1;
    }}
    return 0;
}}
"""


@dataclass(frozen=True, kw_only=True)
class Signature:
    """A Function's name, its inputs' and outputs' names, shapes and nonzeros (column-major)."""

    name: str
    names_in: tuple[str, ...]
    names_out: tuple[str, ...]
    shapes_in: tuple[tuple[int, int], ...]
    shapes_out: tuple[tuple[int, int], ...]
    nnz_in: tuple[int, ...]
    nnz_out: tuple[int, ...]

    @classmethod
    def of(cls, function) -> Signature:
        """The signature of a CasADi Function."""
        return cls(
            name=function.name(),
            names_in=tuple(function.name_in()),
            names_out=tuple(function.name_out()),
            shapes_in=tuple(tuple(function.size_in(i)) for i in range(function.n_in())),
            shapes_out=tuple(tuple(function.size_out(i)) for i in range(function.n_out())),
            nnz_in=tuple(function.nnz_in(i) for i in range(function.n_in())),
            nnz_out=tuple(function.nnz_out(i) for i in range(function.n_out())),
        )

    @classmethod
    def from_json(cls, text: str) -> Signature:
        fields = json.loads(text)
        return cls(
            name=str(fields["name"]),
            names_in=tuple(str(n) for n in fields["names_in"]),
            names_out=tuple(str(n) for n in fields["names_out"]),
            shapes_in=tuple((int(r), int(c)) for r, c in fields["shapes_in"]),
            shapes_out=tuple((int(r), int(c)) for r, c in fields["shapes_out"]),
            nnz_in=tuple(int(n) for n in fields["nnz_in"]),
            nnz_out=tuple(int(n) for n in fields["nnz_out"]),
        )

    def to_json(self) -> str:
        return json.dumps(asdict(self))


def dense_function(function):
    """``function`` with every output dense (a structural zero becomes a 0.0); its inputs must
    be dense already (a sparse input is refused)."""
    import casadi as ca

    for i in range(function.n_in()):
        if not function.sparsity_in(i).is_dense():
            raise ValueError(f"{function.name()}: input '{function.name_in(i)}' is not dense")
    inputs = function.sx_in()
    outputs = [ca.densify(o) for o in function.call(inputs)]
    return ca.Function(function.name(), inputs, outputs, function.name_in(), function.name_out())


def map_source(function) -> str:
    """CasADi's C of the dense ``function`` and its loop over samples (:data:`MAP`)."""
    import casadi as ca

    generator = ca.CodeGenerator(f"{function.name()}.c", {"with_header": False})
    generator.add(function)
    nnz = [function.nnz_out(i) for i in range(function.n_out())]
    return generator.dump() + MAP.format(
        name=function.name(),
        n_in=function.n_in(),
        n_out=function.n_out(),
        nnz_out=", ".join(map(str, nnz)),
        sz_arg=function.sz_arg(),
        sz_res=function.sz_res(),
        sz_iw=function.sz_iw(),
        sz_w=function.sz_w(),
    )


class CompiledFunction:
    """A stored Function (:func:`compiled_function`) called in C with numpy arrays."""

    def __init__(self, signature: Signature, library: ctypes.CDLL) -> None:
        self.signature = signature
        self._map = getattr(library, f"{signature.name}_map")
        self._map.restype = ctypes.c_int

    def __call__(self, *inputs) -> tuple[np.ndarray, ...]:
        """One evaluation: each output a (rows, cols) array, as ``np.asarray`` of CasADi's."""
        return self.map(*inputs)

    def map(self, *inputs) -> tuple[np.ndarray, ...]:
        """Evaluations on ``n`` samples: an input of ``n`` columns (rows x ``n`` cols) gives
        one column block a sample, any other is the same for every sample (as CasADi's
        ``Function.map(n)``); each output is its ``n`` values side by side (rows x ``n``
        cols)."""
        signature = self.signature
        if len(inputs) != len(signature.names_in):
            raise ValueError(f"{signature.name} takes {len(signature.names_in)} inputs")
        n = 1
        arrays, strides = [], []
        for i, value in enumerate(inputs):
            rows, cols = signature.shapes_in[i]
            array = np.asarray(value, dtype=float)
            array = array.reshape(rows, -1) if array.ndim < 2 else array
            if array.shape == (rows, cols):
                arrays.append(np.ravel(array, order="F"))
                strides.append(0)
                continue
            if array.shape[0] != rows or array.shape[1] % cols:
                raise ValueError(
                    f"{signature.name}: input '{signature.names_in[i]}' must have {rows} rows "
                    f"and {cols} columns a sample, got {array.shape}"
                )
            samples = array.shape[1] // cols
            if n not in (1, samples):
                raise ValueError(f"{signature.name}: inputs of {n} and {samples} samples")
            n = samples
            # sample k's block (columns k*cols ...) as one contiguous column-major row
            arrays.append(np.ascontiguousarray(array.T.reshape(samples, cols * rows)))
            strides.append(rows * cols)
        outputs = [np.empty((n, nnz)) for nnz in signature.nnz_out]
        status = self._map(
            ctypes.c_long(n),
            _pointers(arrays),
            (ctypes.c_long * len(strides))(*strides),
            _pointers(outputs),
        )
        if status:
            raise RuntimeError(f"{signature.name} failed in compiled C")
        return tuple(
            out.reshape(n * cols, rows).T
            for out, (rows, cols) in zip(outputs, signature.shapes_out, strict=True)
        )


def _pointers(arrays: list[np.ndarray]) -> ctypes.Array:
    kind = ctypes.POINTER(ctypes.c_double)
    return (kind * max(len(arrays), 1))(*[a.ctypes.data_as(kind) for a in arrays])


def stored_library(
    builder: Callable[[], object], name: str, layout: str, source, *, dense: bool = False
) -> tuple[Signature, ctypes.CDLL]:
    """The Function ``builder()`` (stored, :func:`stored_function`; made ``dense`` if asked)
    and the library of ``source(function)`` (C calling it, laid out as ``layout`` says),
    both known without CasADi when this code built them before: the signature from its
    record (``<builder>_<digest>.signature.json`` in the build folder), the library keyed
    by the code digest, ``layout`` and that signature
    (:func:`~wheelload.models.runtime.build_folder.keyed_library`). CasADi builds them
    otherwise; a record that is not the Function's is made again."""
    stem = builder_stem(builder)
    record = build_folder() / f"{stem}{'.dense' if dense else ''}.signature.json"

    @functools.cache
    def function():
        stored = stored_function(builder)
        return dense_function(stored) if dense else stored

    for _ in range(2):
        try:
            signature = Signature.from_json(record.read_text())
        except (OSError, ValueError, KeyError, TypeError):  # not made yet, or damaged
            signature = Signature.of(function())
            store_text(record, signature.to_json())

        def checked_source(signature=signature) -> str:  # only for the signature recorded
            if Signature.of(function()) != signature:
                raise _Stale
            return source(function())

        key = f"{stem} {layout} {signature.to_json()}"
        try:
            return signature, keyed_library(key, checked_source, name)
        except _Stale:
            record.unlink(missing_ok=True)
    raise RuntimeError(f"{record}: the signature record cannot be made")


class _Stale(Exception):
    """A signature record that is not the Function's (:func:`stored_library`)."""


@functools.cache
def compiled_function(builder: Callable[[], object]) -> CompiledFunction:
    """``builder()``'s Function as compiled C (module docstring): loaded with its signature
    when this code built it before, else built (with CasADi) and stored."""
    name = builder_name(builder)[1].strip("_")
    signature, library = stored_library(builder, f"{name}_map", "map", map_source, dense=True)
    return CompiledFunction(signature, library)
