"""C generation: the KF library, the embedded MHE, the straight-line emitter, batched runs."""
