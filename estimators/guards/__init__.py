"""Guards of the filters' inputs and outputs: plausibility, holds, the innovation gate, the
fault monitor, the load limits, and the layout of their carried state."""
