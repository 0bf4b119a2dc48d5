"""Studies of the tyre forces F_x, F_y per wheel (beside the loads' studies)."""
