"""Tyre forces F_x, F_y per wheel on the two-stage KF's loads: the methods (``forces``) and
their observers' one CasADi step (``step``), which ``wheelload codegen --tyre-forces`` emits."""
