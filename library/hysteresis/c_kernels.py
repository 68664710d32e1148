"""C twins of the hysteresis kernels (:class:`bondgraph.CSource`), for exported models (FMUs).

Each operator of this package returns one of the records below from ``c_source()``; they follow
the Python kernels of ``play.py`` and ``slip.py`` line by line (same operations in the same
order, so the C and numba outputs agree to the last bit on the same input path; the tests
compare them on random paths). Memory layout and parameter vectors are those of the Python
classes.
"""

from __future__ import annotations

from bondgraph import CSource

_PLAY = """static double bg_play(double v, double r, double h)
{
    return fmax(v - r, fmin(v + r, h));
}"""

_FROZEN_PI_SUM = """static double bg_frozen_pi_sum(double v, const double *mem, const double *prm, int n)
{
    double x = 0.0;
    for (int i = 0; i < n; i++) x += prm[n + i] * bg_play(v, prm[i], mem[i]);
    return x;
}"""

_ADVANCE_PLAYS = """static double bg_advance_plays(double v, double *mem, const double *prm, int n)
{
    double x = 0.0;
    for (int i = 0; i < n; i++) {
        mem[i] = bg_play(v, prm[i], mem[i]);
        x += prm[n + i] * mem[i];
    }
    return x;
}"""

_DEAD_ZONE_SUM = """static double bg_dead_zone_sum(double x, const double *prm, int n, int m)
{
    double y = 0.0;
    for (int j = 0; j < m; j++) {
        double d = prm[2 * n + j];
        if (d > 0.0) y += prm[2 * n + m + j] * fmax(0.0, x - d);
        else if (d < 0.0) y += prm[2 * n + m + j] * fmin(0.0, x - d);
        else y += prm[2 * n + m + j] * x;
    }
    return y;
}"""

_BRANCH_GAIN = """static double bg_branch_gain(double u, const double *prm, int n, int m)
{
    double g = 0.0;
    for (int j = 0; j < m; j++) g += prm[2 * n + m + j] * fmax(0.0, u - prm[2 * n + j]);
    return g;
}"""

_VIRGIN_PLAYS = """static void bg_virgin_plays(double v0, const double *r, int n, double *mem)
{
    for (int i = 0; i < n; i++) mem[i] = fmax(v0 - r[i], fmin(v0 + r[i], 0.0));
}"""

_PLAYS = (_PLAY, _VIRGIN_PLAYS, _FROZEN_PI_SUM, _ADVANCE_PLAYS)
_COMMIT_PLAYS = "for (int i = 0; i < n_mem; i++) mem[i] = bg_play(v, prm[i], mem[i]);"
_VIRGIN = "bg_virgin_plays(v0, prm, n_mem, mem);"

#: :class:`~library.hysteresis.PrandtlIshlinskii` (with or without ``prior``)
PI = CSource(
    output="return bg_frozen_pi_sum(v, mem, prm, n_mem);",
    commit=_COMMIT_PLAYS,
    initial="""double prior = n_prm > 2 * n_mem ? prm[2 * n_mem] : 0.0;
for (int i = 0; i < n_mem; i++) mem[i] = fmin(fmax(prior, v0 - prm[i]), v0 + prm[i]);""",
    helpers=_PLAYS,
)

#: :class:`~library.hysteresis.PIStop`
PI_STOP = CSource(
    output="""double y = 0.0;
for (int i = 0; i < n_mem; i++) y += prm[n_mem + i] * (v - bg_play(v, prm[i], mem[i]));
return y;""",
    commit=_COMMIT_PLAYS,
    initial=_VIRGIN,
    helpers=_PLAYS,
)

_DZ = _PLAYS + (_DEAD_ZONE_SUM,)

#: :class:`~library.hysteresis.ModifiedPI`
MODIFIED_PI = CSource(
    output="return bg_dead_zone_sum(bg_frozen_pi_sum(v, mem, prm, n_mem), prm, n_mem, (n_prm - 2 * n_mem) / 2);",
    commit=_COMMIT_PLAYS,
    initial=_VIRGIN,
    helpers=_DZ,
)

#: :class:`~library.hysteresis.InverseModifiedPI`
INVERSE_MODIFIED_PI = CSource(
    output="return bg_frozen_pi_sum(bg_dead_zone_sum(v, prm, n_mem, (n_prm - 2 * n_mem) / 2), mem, prm, n_mem);",
    commit="bg_advance_plays(bg_dead_zone_sum(v, prm, n_mem, (n_prm - 2 * n_mem) / 2), mem, prm, n_mem);",
    initial="bg_virgin_plays(bg_dead_zone_sum(v0, prm, n_mem, (n_prm - 2 * n_mem) / 2), prm, n_mem, mem);",
    helpers=_DZ,
)

_REL = _PLAYS + (_BRANCH_GAIN,)

#: :class:`~library.hysteresis.RelativeModifiedPI`: memory [h_1..h_n, x_r, y_r, s, x_last]
RELATIVE_MODIFIED_PI = CSource(
    output="""int n = n_mem - 4, m = (n_prm - 2 * n) / 2;
double x = bg_frozen_pi_sum(v, mem, prm, n);
double x_r = mem[n], y_r = mem[n + 1], s = mem[n + 2];
if (s * (x - mem[n + 3]) < 0.0) {
    y_r += s * bg_branch_gain(s * (mem[n + 3] - x_r), prm, n, m);
    x_r = mem[n + 3];
    s = -s;
}
return y_r + s * bg_branch_gain(s * (x - x_r), prm, n, m);""",
    commit="""int n = n_mem - 4, m = (n_prm - 2 * n) / 2;
double x = bg_advance_plays(v, mem, prm, n);
double s = mem[n + 2];
if (s * (x - mem[n + 3]) < 0.0) {
    mem[n + 1] += s * bg_branch_gain(s * (mem[n + 3] - mem[n]), prm, n, m);
    mem[n] = mem[n + 3];
    mem[n + 2] = -s;
}
mem[n + 3] = x;""",
    initial="""int n = n_mem - 4;
bg_virgin_plays(v0, prm, n, mem);
double x0 = bg_frozen_pi_sum(v0, mem, prm, n);
mem[n] = 0.0;
mem[n + 1] = 0.0;
mem[n + 2] = x0 >= 0.0 ? 1.0 : -1.0;
mem[n + 3] = x0;""",
    helpers=_REL,
)

#: :class:`~library.hysteresis.InverseRelativeModifiedPI`: memory [h_1..h_n, v_r, x_r, s, v_last]
INVERSE_RELATIVE_MODIFIED_PI = CSource(
    output="""int n = n_mem - 4, m = (n_prm - 2 * n) / 2;
double v_r = mem[n], x_r = mem[n + 1], s = mem[n + 2];
if (s * (v - mem[n + 3]) < 0.0) {
    x_r += s * bg_branch_gain(s * (mem[n + 3] - v_r), prm, n, m);
    v_r = mem[n + 3];
    s = -s;
}
return bg_frozen_pi_sum(x_r + s * bg_branch_gain(s * (v - v_r), prm, n, m), mem, prm, n);""",
    commit="""int n = n_mem - 4, m = (n_prm - 2 * n) / 2;
double s = mem[n + 2];
if (s * (v - mem[n + 3]) < 0.0) {
    mem[n + 1] += s * bg_branch_gain(s * (mem[n + 3] - mem[n]), prm, n, m);
    mem[n] = mem[n + 3];
    s = -s;
    mem[n + 2] = s;
}
bg_advance_plays(mem[n + 1] + s * bg_branch_gain(s * (v - mem[n]), prm, n, m), mem, prm, n);
mem[n + 3] = v;""",
    initial="""int n = n_mem - 4, m = (n_prm - 2 * n) / 2;
double s = v0 >= 0.0 ? 1.0 : -1.0;
bg_virgin_plays(s * bg_branch_gain(fabs(v0), prm, n, m), prm, n, mem);
mem[n] = 0.0;
mem[n + 1] = 0.0;
mem[n + 2] = s;
mem[n + 3] = v0;""",
    helpers=_REL,
)

#: :class:`~library.hysteresis.MaxwellSlip`: prm [k_1..k_n, f_1..f_n], memory the slip positions
MAXWELL_SLIP = CSource(
    output="""double y = 0.0;
for (int i = 0; i < n_mem; i++) y += fmax(-prm[n_mem + i], fmin(prm[n_mem + i], prm[i] * (v - mem[i])));
return y;""",
    commit="""for (int i = 0; i < n_mem; i++) {
    double r = prm[n_mem + i] / prm[i];
    mem[i] = fmax(v - r, fmin(v + r, mem[i]));
}""",
    initial="""for (int i = 0; i < n_mem; i++) {
    double r = prm[n_mem + i] / prm[i];
    mem[i] = fmax(v0 - r, fmin(v0 + r, 0.0));
}""",
)
