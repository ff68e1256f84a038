"""The slew table of scripts/slew_table_example, scripts/python_benchmark and
scripts/slew_table_at_scale: the base scene and the target attitudes."""
import math

# A small imaging satellite: principal moments 9..14 kg m^2 with small products of inertia,
# a 0.5 N m bound on the torque's norm, N = 64 (second_order).
BASE = {"inertia": [[12.0, 0.3, -0.2], [0.3, 14.0, 0.1], [-0.2, 0.1, 9.0]], "steps": 64,
        "scheme": "second_order", "objective": "minimum_time",
        "constraints": [{"max_torque_norm": 0.5}]}


def targets(n):
    """n target attitudes spread over SO(3): axes on a Fibonacci sphere, angles by the golden
    ratio in (0, pi) (deterministic, so the table regenerates identically)."""
    golden = (1 + math.sqrt(5)) / 2
    out = []
    for i in range(n):
        z = 1 - (2 * i + 1) / n
        r = math.sqrt(1 - z * z)
        phi = 2 * math.pi * i / golden
        angle = math.pi * (0.15 + 0.8 * ((i * golden) % 1.0))
        out.append({"name": "T%02d" % (i + 1),
                    "attitude": {"axis": [round(r * math.cos(phi), 6),
                                          round(r * math.sin(phi), 6), round(z, 6)],
                                 "angle": round(angle, 6)}})
    return out
