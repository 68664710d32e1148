"""A linearised model shown in a notebook: its poles with their natural frequencies and
damping ratios, its zeros and its static gain, as an HTML table."""

from __future__ import annotations

import math
from html import escape

import numpy as np


def _complex(z: complex) -> str:
    if abs(z.imag) <= 1e-12 * max(abs(z), 1e-300):
        return f"{z.real:.5g}"
    return f"{z.real:.5g} ± {abs(z.imag):.5g}j"


def _roots_rows(roots: np.ndarray) -> list[str]:
    """One row per real root or conjugate pair: the root, |λ| (rad/s), |λ|/2π (Hz), −Re λ/|λ|."""
    rows = []
    for z in roots[roots.imag >= 0]:
        w = abs(z)
        zeta = f"{-z.real / w:.4g}" if w > 0 else "–"
        rows.append(
            f"<tr><td>{_complex(complex(z))}</td><td>{w:.5g}</td><td>{w / (2 * math.pi):.5g}</td><td>{zeta}</td></tr>"
        )
    return rows


def linear_model_html(lm) -> str:
    """The HTML table of a :class:`~bondgraph.linear.linearize.LinearModel`.

    Parameters
    ----------
    lm : LinearModel
        The linearised model.

    Returns
    -------
    str
        An HTML fragment: input → output, the states, the static gain, then the poles and the
        zeros (one row per real root or conjugate pair, with ω = |λ| in rad/s, f = ω/2π in Hz
        and the damping ratio ζ = −Re λ/|λ|).
    """
    s = lm.summary()
    head = "<tr><th>root (1/s)</th><th>ω (rad/s)</th><th>f (Hz)</th><th>ζ</th></tr>"
    parts = [
        '<div class="bondgraph-linear">',
        f"<p><b>Linear model</b> {escape(s['input'])} → {escape(s['output'])}: {len(s['states'])} states "
        f"({escape(', '.join(s['states']))}); static gain {s['dc_gain']:.5g}; "
        f"{s['rhp_zeros']} right-half-plane zeros</p>",
        f"<table><caption>poles</caption>{head}{''.join(_roots_rows(lm.poles))}</table>",
    ]
    zeros = lm.zeros
    if zeros.size:
        parts.append(f"<table><caption>zeros</caption>{head}{''.join(_roots_rows(zeros))}</table>")
    else:
        parts.append("<p>no finite zeros</p>")
    parts.append("</div>")
    return "\n".join(parts)
