"""The names of a run's metrics (``shc analyze``): written here, below the analysis, because study files name them.

:func:`shc_cli.analysis.metrics.analyze_run` gives every key of :data:`ANALYZE_KEYS`; a study's objectives and
constraints (:mod:`shc_cli.spec.study`) may name any of :data:`OBJECTIVE_KEYS`.
"""

from __future__ import annotations

ANALYZE_KEYS = ("cot", "cot_displacement", "mean_power_w", "mean_speed_mps", "displacement_speed_mps", "path_speed_mps",
                "steady_speed_mps", "commanded_speed_mps", "speed_ratio", "distance_m", "walked_m", "duty_factor",
                "foot_slip_m",
                "height_median_m", "height_iqr_m", "pitch_rate_median_rps", "pitch_rate_iqr_rps",
                "roll_rate_median_rps", "roll_rate_iqr_rps", "stability_margin_median_m", "stability_margin_min_m",
                "zmp_margin_median_m", "zmp_margin_iqr_m", "zmp_centre_distance_median_m", "zmp_centre_distance_iqr_m",
                "gait_cycles", "joint_limit_fraction", "odometry_drift_percent", "odometry_heading_error_deg")
"""The numeric ``shc analyze`` keys, in its output's order."""
OBJECTIVE_KEYS = tuple(key for key in ANALYZE_KEYS if key != "gait_cycles")
"""The analyze keys a study's objectives and constraints may name (a count of cycles is no quality)."""
