"""Bounds of the compiled single C step: measured clock, instruction mix, throughput.

Used by ``wheelload bench speed`` to put the single step's time beside

- its dependency-chain bound (:func:`~wheelload.estimators.kernels.c_emitter.critical_path`,
  cycles) at the clock the core actually runs, measured here by a chain of
  dependent 64-bit register multiplies (``imul r64, r64``: :data:`IMUL_LATENCY` cycles
  each on every Intel core since Nehalem and every AMD Zen; a multiply cannot be folded
  at rename, as a chain of ``add $1`` is on Intel cores from Golden Cove on, which made
  that chain report several times the true clock): the ``cpu MHz`` of ``/proc/cpuinfo``
  is the nominal clock, and a boosting core runs faster;
- a throughput bound from the compiled kernel's instructions
  (``objdump -d``): on AMD Zen 3/4, multiplies, FMAs and ``blendv`` share
  two pipes, additions, compares and ``min``/``max`` two others, a scalar
  division occupies the divider for about 5 cycles, and at most 6
  instructions are dispatched per cycle (pipe sharing measured on this
  machine with back-to-back independent instructions). The largest of
  these is the fewest cycles the instruction stream can take whatever
  the dependencies.

Printed, never asserted.
"""

from __future__ import annotations

import collections
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from wheelload.studies.bench.c_clock import SECONDS

#: Dispatch width and pipes of the throughput model (AMD Zen 3/4).
DISPATCH_WIDTH = 6
MULTIPLY_PIPES = 2
ADD_PIPES = 2
DIVIDER_CYCLES = 5

_MULTIPLY = re.compile(r"^v(mul|fn?madd|fn?msub|blendv)\w*s[sd]$|^vblendvp[sd]$")
_ADD = re.compile(r"^v(add|sub|cmp\w*|max|min)s[sd]$")
_DIVIDE = re.compile(r"^v(div|sqrt)s[sd]$")

#: Latency of ``imul r64, r64`` [cycles] (Intel since Nehalem, AMD Zen 1-5; Agner Fog's
#: instruction tables), the link of the clock's dependent chain.
IMUL_LATENCY = 3
#: Links of the chain per timed run.
CLOCK_CHAIN = 1_000_000

_CLOCK_SOURCE = (
    SECONDS
    + r"""
#include <stdio.h>
int main(void)
{
    double best = 1e9;
    long x = 3;
    const long factor = 5;
    int r;
    for (r = 0; r < 300; ++r) {
        double start = seconds(), elapsed;
        long i;
        for (i = 0; i < CHAIN / 500; ++i) {
            __asm__ volatile(".rept 500\n\timul %1, %0\n\t.endr" : "+r"(x) : "r"(factor));
        }
        elapsed = seconds() - start;
        best = elapsed < best ? elapsed : best;
    }
    printf("%.1f\n", (double)CHAIN * LATENCY / best * 1e-6);
    return x == 0;
}
"""
)


def measured_clock_mhz(folder: Path, compiler: str = "gcc") -> float | None:
    """Clock the core runs at [MHz]: :data:`CLOCK_CHAIN` dependent multiplies of
    :data:`IMUL_LATENCY` cycles each, fastest of 300 runs.

    None off x86-64 or when the helper cannot be built.
    """
    source, binary = folder / "clock.c", folder / "clock"
    source.write_text(_CLOCK_SOURCE)
    built = subprocess.run(
        [
            compiler,
            "-O2",
            f"-DCHAIN={CLOCK_CHAIN}L",
            f"-DLATENCY={IMUL_LATENCY}.0",
            "-o",
            str(binary),
            str(source),
        ],
        capture_output=True,
        text=True,
    )
    if built.returncode != 0:
        return None
    out = subprocess.run([str(binary)], capture_output=True, text=True)
    try:
        return float(out.stdout)
    except ValueError:
        return None


def kernel_instructions(obj: Path, symbol: str) -> collections.Counter[str] | None:
    """Mnemonic counts of function ``symbol`` in object file ``obj`` (None without objdump)."""
    if shutil.which("objdump") is None:
        return None
    text = subprocess.run(
        ["objdump", "-d", "--no-show-raw-insn", str(obj)], capture_output=True, text=True
    ).stdout
    counts: collections.Counter[str] = collections.Counter()
    inside = False
    for line in text.splitlines():
        if line.endswith(f"<{symbol}>:"):
            inside = True
            continue
        if inside and not line.strip():
            break
        if inside:
            fields = line.split("\t")
            if len(fields) >= 2 and fields[1].strip():
                counts[fields[1].split()[0]] += 1
    return counts or None


@dataclass(frozen=True, kw_only=True)
class InstructionMix:
    """What the compiled kernel executes, by pipe of the throughput model."""

    instructions: int
    multiply: int  # mul, FMA, blendv
    add: int  # add, sub, compare, min, max
    divide: int  # div, sqrt
    stack: int  # instructions that read or write the stack (spills, reloads)
    branches: int

    @classmethod
    def of(cls, counts: collections.Counter[str], stack: int) -> InstructionMix:
        def total(pattern: re.Pattern[str]) -> int:
            return sum(n for name, n in counts.items() if pattern.match(name))

        return cls(
            instructions=sum(counts.values()),
            multiply=total(_MULTIPLY),
            add=total(_ADD),
            divide=total(_DIVIDE),
            stack=stack,
            branches=sum(n for name, n in counts.items() if name.startswith("j")),
        )

    def bounds(self) -> dict[str, float]:
        """Cycles each resource needs for one step."""
        return {
            "dispatch": self.instructions / DISPATCH_WIDTH,
            "multiply pipes": self.multiply / MULTIPLY_PIPES,
            "add pipes": self.add / ADD_PIPES,
            "divider": self.divide * DIVIDER_CYCLES,
        }

    def throughput_bound(self) -> float:
        """The largest of :meth:`bounds` [cycles]."""
        return max(self.bounds().values())


def compiled_mix(
    source: Path, symbol: str, flags: tuple[str, ...], compiler: str = "gcc"
) -> InstructionMix | None:
    """Compile ``source`` to an object with ``flags`` and count ``symbol``'s instructions."""
    obj = source.with_suffix(".mix.o")
    built = subprocess.run(
        [compiler, *flags, "-c", "-o", str(obj), str(source)], capture_output=True, text=True
    )
    if built.returncode != 0:
        return None
    counts = kernel_instructions(obj, symbol)
    if counts is None:
        return None
    text = subprocess.run(
        ["objdump", "-d", "--no-show-raw-insn", str(obj)], capture_output=True, text=True
    ).stdout
    body = text.split(f"<{symbol}>:", 1)[1].split("\n\n", 1)[0]
    return InstructionMix.of(counts, stack=body.count("(%rsp)"))
