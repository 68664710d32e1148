"""Measured-data CSV format (bondgraph.data) and atomic file output (bondgraph.support.atomic)."""

from __future__ import annotations

import json
import os
import stat
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from bondgraph.data import Dataset, DataWarning, check_units, read_csv, write_csv
from bondgraph.support.atomic import atomic_write
from bondgraph.support.errors import BondGraphError, DataError, UsageError

FAST = settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)


def _write(tmp_path, content, name="data.csv"):
    p = tmp_path / name
    p.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
    return p


def _read_quiet(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)
        return read_csv(path, **kw)


def _same_bits(a, b):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def _assert_one_line(err, path, line=None):
    msg = str(err)
    assert "\n" not in msg and "\r" not in msg
    prefix = f"{path}:" if line is None else f"{path}:{line}: "
    assert msg.startswith(prefix), f"expected {prefix!r}, got {msg!r}"


# --------------------------------------------------------------------------- strategies

finite = st.floats(allow_nan=False, allow_infinity=False)
simple_names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,6}", fullmatch=True)
odd_names = st.text(
    alphabet=st.characters(blacklist_characters=',\n\r"', blacklist_categories=("Cs",)),
    min_size=1,
    max_size=6,
).filter(lambda s: s == s.strip() and not s.startswith("#"))
column_names = st.lists(st.one_of(simple_names, odd_names).filter(lambda s: s != "t"), max_size=4, unique=True)
meta_keys = st.one_of(
    st.from_regex(r"[A-Za-z_][A-Za-z0-9_ .\-/()\[\]]{0,10}", fullmatch=True),
    st.text(
        alphabet=st.characters(blacklist_characters=":#\n\r", blacklist_categories=("Cs",)), min_size=1, max_size=10
    ),
).filter(lambda k: k == k.strip() and (k[0].isalpha() or k[0] == "_") and k[0].isidentifier())
meta_values = st.one_of(
    st.text(alphabet=st.characters(blacklist_characters="\n\r", blacklist_categories=("Cs",)), max_size=20),
    finite,
    st.integers(),
)


@st.composite
def datasets(draw, min_rows=2, max_rows=30):
    t = sorted(draw(st.lists(finite, min_size=min_rows, max_size=max_rows, unique=True)))
    names = draw(column_names)
    table = draw(arrays(np.float64, (len(t), len(names)), elements=finite))
    metadata = draw(st.dictionaries(meta_keys, meta_values, max_size=4))
    return np.array(t), {n: table[:, j] for j, n in enumerate(names)}, metadata


# --------------------------------------------------------------------------- round trip


@FAST
@given(data=datasets())
def test_write_read_round_trip_is_exact(tmp_path, data):
    t, columns, metadata = data
    p = tmp_path / "rt.csv"
    write_csv(p, t, columns, metadata)
    ds = _read_quiet(p)
    assert _same_bits(ds.t, t)
    assert list(ds.columns) == list(columns)
    for name, values in columns.items():
        assert _same_bits(ds.columns[name], values), name
    assert ds.metadata == {k: str(v).strip() for k, v in metadata.items()}
    assert list(ds.metadata) == list(metadata)
    assert ds.path == str(p) and len(ds) == len(t)


@FAST
@given(
    data=datasets(max_rows=12),
    inserts=st.lists(
        st.tuples(st.integers(0, 20), st.sampled_from(["", "   ", "# note", "  # k9: v 9", "#"])), max_size=5
    ),
)
def test_comments_and_blank_lines_between_rows_change_nothing(tmp_path, data, inserts):
    t, columns, _ = data
    p = tmp_path / "cm.csv"
    write_csv(p, t, columns)
    lines = p.read_text(encoding="utf-8").split("\n")
    for pos, extra in inserts:
        lines.insert(1 + pos % len(lines), extra)  # never before the header
    p.write_text("\n".join(lines), encoding="utf-8")
    ds = _read_quiet(p)
    assert _same_bits(ds.t, t)
    for name, values in columns.items():
        assert _same_bits(ds.columns[name], values)
    if any(extra.strip().startswith("# k9:") for _, extra in inserts):
        assert ds.metadata == {"k9": "v 9"}


@FAST
@given(
    rows=st.integers(3, 15),
    bad_row=st.integers(0, 14),
    defect=st.sampled_from(["abc", "", "nan", "-inf", "1e999", "cells", "time"]),
    inserts=st.lists(st.tuples(st.integers(0, 30), st.sampled_from(["", "# c", "# a: b"])), max_size=4),
    crlf=st.booleans(),
)
def test_reported_line_is_the_bad_line(tmp_path, rows, bad_row, defect, inserts, crlf):
    bad_row %= rows
    lines = ["# source: test", "t,V,x"] + [f"{k},{k * 0.5},{k * 1e-6}" for k in range(rows)]
    i = 2 + bad_row
    if defect == "cells":
        lines[i] += ",7"
    elif defect == "time":
        if bad_row == 0:
            bad_row, i = 1, 3
        lines[i] = f"{bad_row - 1},0,0"
    else:
        lines[i] = f"{bad_row},{defect},0"
    marked = list(lines)
    marked[i] = ("BAD", lines[i])
    for pos, extra in inserts:
        marked.insert(2 + pos % (len(marked) - 1), extra)
    expected = next(k for k, m in enumerate(marked, 1) if isinstance(m, tuple))
    text = "\n".join(m[1] if isinstance(m, tuple) else m for m in marked)
    p = _write(tmp_path, text.replace("\n", "\r\n") if crlf else text, "bad.csv")
    with pytest.raises(DataError) as exc:
        read_csv(p)
    _assert_one_line(exc.value, p, expected)


@settings(FAST, max_examples=150)
@given(
    st.one_of(
        st.text(alphabet="tVx019.,e-+#: \n\r\tabn\ufeff", max_size=60),
        st.binary(max_size=40),
    )
)
def test_any_input_gives_dataset_or_one_line_data_error(tmp_path, content):
    p = tmp_path / "fz.csv"
    p.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
    try:
        ds = _read_quiet(p)
    except DataError as err:
        _assert_one_line(err, p)
    else:
        assert len(ds) >= 2 and (np.diff(ds.t) > 0).all()
        assert all(np.isfinite(v).all() for v in ds.columns.values())


def test_large_file_round_trip(tmp_path):
    n = 250_000
    rng = np.random.default_rng(1)
    t = np.arange(n) * 1e-4
    cols = {"V": 50 * np.sin(2 * np.pi * 10 * t), "x": rng.normal(0, 1e-5, n)}
    p = tmp_path / "big.csv"
    write_csv(p, t, cols, {"actuator": "APA120ML"})
    ds = read_csv(p)
    assert len(ds) == n and _same_bits(ds.t, t)
    assert _same_bits(ds.input(), cols["V"]) and _same_bits(ds.output(), cols["x"])
    assert ds.metadata == {"actuator": "APA120ML"}
    assert ds.is_uniform and ds.sample_rate == pytest.approx(1e4)


# --------------------------------------------------------------------------- accepted variants


def test_bom_crlf_metadata_and_quoted_header(tmp_path):
    content = (
        "\ufeff# actuator: APA120ML\r\n#free comment\r\n# gain (V/V): 20 : x\r\n"
        '"t", V ,x\r\n0,1,2e-6\r\n\r\n1e-3, 2 ,3e-6\r\n# end: yes\r\n'
    )
    ds = read_csv(_write(tmp_path, content))
    assert ds.metadata == {"actuator": "APA120ML", "gain (V/V)": "20 : x", "end": "yes"}
    assert list(ds.columns) == ["V", "x"]
    np.testing.assert_array_equal(ds.t, [0, 1e-3])
    np.testing.assert_array_equal(ds.input(), [1, 2])


def test_lone_cr_and_no_final_newline(tmp_path):
    ds = read_csv(_write(tmp_path, "t,V\r0,1\r1,2"))
    np.testing.assert_array_equal(ds.columns["V"], [1, 2])


def test_single_column_and_extra_columns_are_kept(tmp_path):
    assert list(read_csv(_write(tmp_path, "t\n0\n1\n")).columns) == []
    ds = read_csv(_write(tmp_path, "t,V,x,F,temp\n0,1,0,0,20\n1,2,0,0,21\n"))
    assert ds.names == ("t", "V", "x", "F", "temp")


# --------------------------------------------------------------------------- refused files

BAD_FILES = [
    # id, content, line, substring
    ("empty", b"", 1, "empty"),
    ("blank", b"\n  \n\n", 1, "empty"),
    ("only-comments", b"# a: 1\n# b\n", 2, "only comments"),
    ("header-only", b"t,V,x\n", 1, "no data rows"),
    ("header-and-comments", b"# c\nt,V,x\n# end\n\n", 2, "no data rows"),
    ("one-row", b"t,V,x\n0,1,2\n", 2, "only 1 data row"),
    ("no-t", b"time,V,x\n0,1,2\n1,2,3\n", 1, "missing required column 't'"),
    ("duplicate", b"t,V,V\n0,1,2\n1,2,3\n", 1, "duplicate column name 'V' (columns 2 and 3)"),
    ("empty-name", b"t,,x\n0,1,2\n1,2,3\n", 1, "column 2"),
    ("header-trailing-comma", b"t,V,\n0,1,2\n1,2,3\n", 1, "trailing comma"),
    ("numeric-header", b"0,1,2\n1,2,3\n", 1, "header"),
    ("commented-header", b"# t,V,x\n0,1,2\n1,2,3\n", 2, "commented out at line 1"),
    ("semicolons", b"t;V;x\n0;1;2\n", 1, "semicolon"),
    ("too-many-cells", b"t,V,x\n0,1,2\n1,2,3,4\n2,3,4\n", 3, "4 cells"),
    ("too-few-cells", b"t,V,x\n0,1,2\n1,2\n2,3,4\n", 3, "2 cells"),
    ("row-trailing-comma", b"t,V,x\n0,1,2\n1,2,3,\n", 3, "trailing comma"),
    ("all-rows-short", b"t,V,x\n0,1\n1,2\n", 2, "2 cells"),
    ("non-numeric", b"t,V,x\n0,1,2\n1,abc,3\n", 3, "non-numeric cell 'abc' in column 'V'"),
    ("quoted-number", b't,V,x\n0,1,2\n1,"2",3\n', 3, "non-numeric cell '\"2\"'"),
    ("empty-cell", b"t,V,x\n0,1,2\n1,,3\n", 3, "empty cell in column 'V'"),
    ("nan", b"t,V,x\n0,1,2\n1,2,3\n2,3,nan\n", 4, "'nan' in column 'x'"),
    ("NaN-in-t", b"t,V\n0,1\nNaN,2\n", 3, "'NaN' in column 't'"),
    ("inf", b"t,V,x\n0,1,2\n1,-inf,3\n", 3, "'-inf'"),
    ("overflow", b"t,V,x\n0,1,2\n1,1e999,3\n", 3, "overflows"),
    ("time-repeated", b"t,V,x\n0,1,2\n1,2,3\n1,3,4\n", 4, "t = 1 at line 4 follows t = 1 at line 3"),
    ("time-decreasing", b"t,V\n0,1\n2,2\n1.5,3\n", 4, "not strictly increasing"),
    ("time-after-comments", b"# a: 1\nt,V,x\n0,1,2\n# mid\n\n2,2,3\n1,3,4\n", 7, "line 6"),
    ("nan-after-prelude", b"# a\n# b\n\nt,V\n0,1\n1,nan\n", 6, "'nan'"),
    ("bad-utf8", b"t,V,x\n0,1,2\n1,\xff,3\n", 3, "not valid UTF-8 (byte 0xff at column 3)"),
    ("utf16", "t,V\n0,1\n1,2\n".encode("utf-16"), 1, "UTF-16"),
    ("crlf-error", b"t,V,x\r\n0,1,2\r\n1,x,3\r\n", 3, "'x'"),
    ("decimal-comma", b"t;V\n0;1,5\n", 1, "semicolon"),
]


@pytest.mark.parametrize("content,line,needle", [b[1:] for b in BAD_FILES], ids=[b[0] for b in BAD_FILES])
def test_bad_file_is_refused_with_file_and_line(tmp_path, content, line, needle):
    p = _write(tmp_path, content, "bad data.csv")
    with pytest.raises(DataError) as exc:
        read_csv(p)
    _assert_one_line(exc.value, p, line)
    assert needle in str(exc.value)
    assert isinstance(exc.value, BondGraphError) and isinstance(exc.value, ValueError)


def test_missing_required_columns_name_found_columns_and_mapping(tmp_path):
    p = _write(tmp_path, "# c\nt,Vin,disp\n0,1,2\n1,2,3\n")
    with pytest.raises(DataError) as exc:
        read_csv(p, required=("t", "V", "x"))
    msg = str(exc.value)
    _assert_one_line(exc.value, p, 2)
    assert "'V', 'x'" in msg and "t, Vin, disp" in msg and "--input COL" in msg
    with pytest.raises(DataError, match="--output COL"):
        read_csv(p, required=("x",), rename={"Vin": "V"})


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(DataError) as exc:
        read_csv(tmp_path / "nope.csv")
    _assert_one_line(exc.value, tmp_path / "nope.csv")
    assert "no such file" in str(exc.value)
    with pytest.raises(DataError, match="directory"):
        read_csv(tmp_path)


# --------------------------------------------------------------------------- rename


def test_rename_maps_file_columns_to_canonical_names(tmp_path):
    p = _write(tmp_path, "t,Vin,disp,V\n0,1,2e-6,9e-6\n1,2,3e-6,9e-6\n")
    ds = read_csv(p, required=("t", "V", "x"), rename={"Vin": "V", "disp": "x"})
    assert list(ds.columns) == ["V", "x"]  # the file's own 'V' yields to the mapped one
    np.testing.assert_array_equal(ds.input(), [1, 2])
    np.testing.assert_array_equal(ds.output(), [2e-6, 3e-6])
    swapped = read_csv(p, rename={"V": "x", "disp": "V"})
    np.testing.assert_array_equal(swapped.columns["x"], [9e-6, 9e-6])


def test_rename_of_unknown_column_lists_columns(tmp_path):
    p = _write(tmp_path, "t,V,x\n0,1,2e-6\n1,2,3e-6\n")
    with pytest.raises(DataError) as exc:
        read_csv(p, rename={"volt": "V"})
    _assert_one_line(exc.value, p, 1)
    assert "'volt'" in str(exc.value) and "t, V, x" in str(exc.value)
    with pytest.raises(UsageError):
        read_csv(p, rename={"V": "y", "x": "y"})


# --------------------------------------------------------------------------- unit sanity


def test_micrometre_displacement_warns(tmp_path):
    p = _write(tmp_path, "t,V,x\n0,0,0\n0.001,10,12.5\n0.002,20,25\n")
    with pytest.warns(DataWarning, match=r"micrometres|µm") as rec:
        ds = read_csv(p)
    msg = str(rec[0].message)
    assert "1e-6" in msg and str(p) in msg and "\n" not in msg
    assert ds.output()[2] == 25  # warned, not changed
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_csv(p, check_units=False)


def test_plausible_data_does_not_warn(tmp_path):
    t = np.linspace(0, 2000, 2001)  # a 1 Hz creep record, 33 min
    p = tmp_path / "ok.csv"
    write_csv(p, t, {"V": np.full_like(t, 100.0), "x": 1e-4 * (1 - np.exp(-t / 100))})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_csv(p)


def test_millisecond_time_warns():
    t = np.arange(20000.0)  # 20 s at 1 kHz written in ms
    ds = Dataset(t, {"x": np.zeros_like(t)})
    with pytest.warns(DataWarning, match="milliseconds"):
        assert len(check_units(ds)) == 1


# --------------------------------------------------------------------------- write_csv


def test_write_csv_layout(tmp_path):
    p = tmp_path / "out.csv"
    meta = {"model": "stack", "n": 3, "param k1": "[1 2\n 3]", "input V": "sine(a=1)"}
    write_csv(p, [0.0, 0.1], {"V": [1, 2], "x": [1e-6, -0.0]}, meta)
    assert p.read_bytes() == (
        b"# model: stack\n# n: 3\n# param k1: [1 2 3]\n# input V: sine(a=1)\nt,V,x\n0.0,1.0,1e-06\n0.1,2.0,-0.0\n"
    )
    assert read_csv(p).metadata == {"model": "stack", "n": "3", "param k1": "[1 2 3]", "input V": "sine(a=1)"}


@pytest.mark.parametrize(
    "t,columns,metadata,needle",
    [
        ([0, 1], {"x": [0, np.nan]}, None, "non-finite"),
        ([0, 0], {"x": [0, 1]}, None, "not strictly increasing"),
        ([0, 1], {"x": [0, 1, 2]}, None, "same length"),
        ([0, 1], {"a,b": [0, 1]}, None, "column name"),
        ([0, 1], {" x": [0, 1]}, None, "column name"),
        ([0, 1], {"t": [0, 1]}, None, "time axis"),
        ([0, 1], {"x": [0, 1]}, {"1st": "a"}, "metadata key"),
        ([0, 1], {"x": [0, 1]}, {"a:b": "a"}, "metadata key"),
        ([0, 1], {"x": [0, 1]}, {"a#": "a"}, "metadata key"),
    ],
)
def test_write_csv_refuses_what_read_csv_would_refuse(tmp_path, t, columns, metadata, needle):
    p = tmp_path / "out.csv"
    p.write_text("previous")
    with pytest.raises(DataError, match=needle) as exc:
        write_csv(p, t, columns, metadata)
    _assert_one_line(exc.value, p)
    assert p.read_text() == "previous" and os.listdir(tmp_path) == ["out.csv"]


def test_write_csv_into_missing_directory(tmp_path):
    p = tmp_path / "no" / "out.csv"
    with pytest.raises(DataError) as exc:
        write_csv(p, [0, 1], {"x": [0, 1]})
    _assert_one_line(exc.value, p)


# --------------------------------------------------------------------------- atomic_write


@pytest.mark.parametrize("exc_type", [RuntimeError, KeyboardInterrupt])
def test_atomic_write_failure_leaves_nothing(tmp_path, exc_type):
    p = tmp_path / "out.csv"
    with pytest.raises(exc_type):
        with atomic_write(p) as f:
            f.write("half a file")
            raise exc_type()
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("exc_type", [RuntimeError, KeyboardInterrupt])
def test_atomic_write_failure_keeps_previous_file(tmp_path, exc_type):
    p = tmp_path / "out.json"
    p.write_text('{"old": 1}')
    with pytest.raises(exc_type):
        with atomic_write(p) as f:
            json.dump({"new": 2}, f)
            f.flush()
            raise exc_type()
    assert json.loads(p.read_text()) == {"old": 1}
    assert os.listdir(tmp_path) == ["out.json"]


def test_atomic_write_replaces_and_keeps_permissions(tmp_path):
    ref = tmp_path / "ref"
    ref.write_text("")
    p = tmp_path / "new.json"
    with atomic_write(p) as f:
        json.dump({"a": [1, 2]}, f)
    assert json.loads(p.read_text()) == {"a": [1, 2]}
    assert stat.S_IMODE(p.stat().st_mode) == stat.S_IMODE(ref.stat().st_mode)
    os.chmod(p, 0o600)
    with atomic_write(p, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
    assert p.read_bytes() == b"\x89PNG\r\n\x1a\n"
    assert stat.S_IMODE(p.stat().st_mode) == 0o600
    with atomic_write(p) as f:  # a writer that closes the file itself
        f.write("closed early")
        f.close()
    assert p.read_text() == "closed early"
    assert sorted(os.listdir(tmp_path)) == ["new.json", "ref"]
    with pytest.raises(ValueError):
        with atomic_write(p, "a"):
            pass


def test_atomic_write_matplotlib_png(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    p = tmp_path / "fig.png"
    with atomic_write(p, "wb") as f:
        fig.savefig(f, format="png")
    plt.close(fig)
    assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and os.listdir(tmp_path) == ["fig.png"]


# --------------------------------------------------------------------------- Dataset helpers


def _sine(n=4000, fs=1e4, f=20.0):
    t = np.arange(n) / fs
    return Dataset(t, {"V": np.sin(2 * np.pi * f * t), "x": 1e-6 * np.cos(2 * np.pi * f * t)}, {"k": "v"})


def test_dataset_basics_and_immutability():
    ds = _sine()
    assert len(ds) == 4000 and ds.sample_rate == pytest.approx(1e4) and ds.is_uniform
    assert ds.names == ("t", "V", "x") and "rows=4000" in repr(ds)
    with pytest.raises(ValueError):
        ds.t[0] = 1.0
    with pytest.raises(ValueError):
        ds.input()[0] = 1.0
    src = np.array([0.0, 1.0])
    Dataset(src, {})
    src[0] = -1.0  # the caller's array stays writable (the dataset holds a copy)
    with pytest.raises(DataError, match="--input"):
        ds.input("Vin")
    with pytest.raises(DataError, match="--output"):
        ds.output("y")
    with pytest.raises(DataError, match="non-finite"):
        Dataset([0, 1], {"x": [0, np.inf]})
    with pytest.raises(DataError, match="at least 2"):
        Dataset([0.0], {})


def test_slice_and_split():
    ds = _sine(n=1001)
    part = ds.slice(0.01, 0.02)
    assert part.t[0] == pytest.approx(0.01) and part.t[-1] == pytest.approx(0.02)
    assert len(part) == 101 and part.metadata == {"k": "v"}
    fit, val = ds.split(0.7)
    assert len(fit) + len(val) == len(ds) and fit.t[-1] < val.t[0]
    assert fit.t[-1] < ds.t[0] + 0.7 * ds.duration <= val.t[0]
    np.testing.assert_array_equal(np.concatenate([fit.input(), val.input()]), ds.input())
    with pytest.raises(UsageError):
        ds.split(1.0)
    with pytest.raises(DataError):
        ds.slice(5.0, 6.0)


def test_decimate_keeps_band_and_needs_uniform_sampling():
    ds = _sine(n=20000, fs=1e4, f=5.0)
    for factor in (20, 100):  # 100 runs in two IIR stages
        d = ds.decimate(factor)
        assert len(d) == len(ds.t[::factor]) and np.array_equal(d.t, ds.t[::factor])
        mid = slice(len(d) // 4, 3 * len(d) // 4)
        # passband ripple of the Chebyshev filter: 0.05 dB, twice (zero phase) per stage
        np.testing.assert_allclose(d.input()[mid], ds.input()[::factor][mid], atol=0.03)
    assert ds.decimate(1) is ds
    uneven = Dataset(np.cumsum(np.r_[0, np.tile([1.0, 1.5], 50)]), {"x": np.zeros(101)})
    assert not uneven.is_uniform
    with pytest.raises(DataError, match="resample"):
        uneven.decimate(2)
    with pytest.raises(UsageError):
        ds.decimate(0)


def test_resample_interpolates_onto_uniform_grid():
    t = np.cumsum(np.r_[0, np.tile([1.0, 1.5], 50)]) * 1e-3
    ds = Dataset(t, {"x": 2 * t + 1})
    r = ds.resample(1e-3)
    assert r.is_uniform and r.t[0] == t[0] and r.t[-1] <= t[-1]
    np.testing.assert_allclose(r.output(), 2 * r.t + 1, rtol=1e-12)


# --------------------------------------------------------------------------- one definition of uniform sampling


def test_uniform_sampling_has_one_definition_and_a_config_tolerance():
    from bondgraph import config
    from bondgraph.data import uniform_step
    from bondgraph.fit import identify

    assert identify.uniform_step is uniform_step
    t = np.cumsum(np.r_[0, np.tile([1.0, 1.01], 50)])  # steps 0.5 % from the mean
    ds = Dataset(t, {"x": np.zeros_like(t)})
    assert ds.is_uniform and uniform_step(t) == pytest.approx(1.005)
    with config.override({"data.uniform_rtol": 1e-3}):
        assert not ds.is_uniform and uniform_step(t) is None


def test_unit_checks_of_the_physics_come_from_installed_libraries():
    from bondgraph.data.checks import installed_checks
    from library.data_checks import displacement_in_metres

    assert displacement_in_metres in installed_checks()
    ds = Dataset([0.0, 1.0, 2.0], {"V": [0.0, 1.0, 2.0], "x": [0.0, 3.0, 6.0]})
    assert len(displacement_in_metres(ds)) == 1
    assert not displacement_in_metres(Dataset([0.0, 1.0], {"V": [0.0, 100.0]}))
