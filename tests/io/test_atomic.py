"""profileopt.io.atomic: outputs written all or none, streams before files, through symlinks,
and never onto an input, even when a folder is swapped while the command runs (issue 30,
items 2, 6 and 7; picture formats, item 14).

These run the output set directly (no planning), so each takes milliseconds; the command
line's use of it is covered by tests/cli/test_outputs.py and tests/cli/test_app.py.
"""

from __future__ import annotations

import errno
import io
import os
from pathlib import Path

import pytest

from profileopt.errors import InputError
from profileopt.io.atomic import OutputSet, atomic_path, atomic_write, picture_format

DEV_FULL = Path("/dev/full")
needs_dev_full = pytest.mark.skipif(not DEV_FULL.exists(), reason="needs /dev/full (Linux)")


def write_all(outputs: OutputSet, texts: dict[str, str]) -> None:
    """Write each path's text inside the set, as a command does."""
    with outputs:
        for path, text in texts.items():
            with atomic_write(path) as handle:
                handle.write(text)


def no_temporary_files(folder: Path) -> bool:
    return not [p for p in folder.rglob(".po-*.tmp")]


# --------------------------------------------------------------------------------------
# Item 2: a stream that fails leaves every file as it was.


@needs_dev_full
@pytest.mark.parametrize("order", ["stream first", "file first"])
def test_a_full_stream_leaves_the_files_as_they_were(tmp_path: Path, order: str) -> None:
    old = tmp_path / "old.png"
    old.write_bytes(b"a good earlier plot")
    outputs = [("-o", str(DEV_FULL), True), ("--plot", str(old))]
    if order == "file first":
        outputs.reverse()
    with pytest.raises(InputError, match=r"-o /dev/full: cannot write it \(No space left on device\)"):
        write_all(OutputSet(outputs), {str(DEV_FULL): "a profile\n", str(old): "a new plot"})
    assert old.read_bytes() == b"a good earlier plot"
    assert no_temporary_files(tmp_path)


@needs_dev_full
def test_without_a_set_a_full_device_is_one_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot write it"):
        with atomic_write(DEV_FULL) as handle:
            handle.write("x" * 100_000)


class FullStream(io.StringIO):
    """A text stream on a full disk: what is written cannot be flushed (``> /dev/full``)."""

    def flush(self) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")


def test_what_a_command_prints_goes_before_the_renames(tmp_path: Path) -> None:
    # Before: the summary was printed after the files were renamed into place, so
    # `plan ... -o old.csv --plot old.png > /dev/full` replaced both files, then said exit 2
    old = tmp_path / "old.csv"
    old.write_text("a good earlier profile\n")
    outputs = OutputSet([("-o", str(old), True)])
    with pytest.raises(InputError) as raised:
        with outputs:
            with atomic_write(old) as handle:
                handle.write("a new profile\n")
            outputs.print("travel time 12 s", FullStream())
    message = str(raised.value)
    assert "\n" not in message and "cannot write (No space left on device); no file output was written" in message
    assert old.read_text() == "a good earlier profile\n"
    assert no_temporary_files(tmp_path)


def test_printed_text_is_written_once_the_outputs_are_ready(tmp_path: Path) -> None:
    stream, seen = io.StringIO(), []
    out = tmp_path / "out.csv"
    with OutputSet([("-o", str(out), True)]) as outputs:
        with atomic_write(out) as handle:
            handle.write("new\n")
        outputs.print("summary", stream)
        seen.append((stream.getvalue(), out.exists()))  # nothing printed, nothing renamed yet
    assert seen == [("", False)]
    assert stream.getvalue() == "summary\n" and out.read_text() == "new\n"


def test_a_reusable_set_writes_again_in_the_folder_it_checked(tmp_path: Path) -> None:
    # a batch rewrites its summary after every route: the folder checked at the start is held
    # open, so a folder swapped for a link to the inputs' folder between two writes replaces nothing
    inputs, out = tmp_path / "inputs", tmp_path / "out"
    inputs.mkdir()
    out.mkdir()
    manifest = inputs / "summary.csv"
    manifest.write_text("the manifest\n")
    outputs = OutputSet([("summary", str(out / "summary.csv"))], inputs=[str(manifest)], reusable=True)
    try:
        for text in ("first\n", "second\n"):
            write_all(outputs, {str(out / "summary.csv"): text})
        assert (out / "summary.csv").read_text() == "second\n"
        _swap(tmp_path, out, inputs)
        with pytest.raises(InputError, match="is now the input"):
            write_all(outputs, {str(out / "summary.csv"): "third\n"})
    finally:
        outputs.close()
    assert manifest.read_text() == "the manifest\n"
    assert (tmp_path / "out.old" / "summary.csv").read_text() == "second\n"
    assert no_temporary_files(tmp_path)


# --------------------------------------------------------------------------------------
# Item 6: a symlink is written through to its target, and stays a link.


def test_a_symlink_output_writes_its_target_and_stays_a_link(tmp_path: Path) -> None:
    (tmp_path / "data").mkdir()
    target = tmp_path / "data" / "profile.csv"
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    write_all(OutputSet([("-o", str(link), True)]), {str(link): "new\n"})
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_text() == "new\n"
    assert no_temporary_files(tmp_path)


def test_a_dangling_symlink_output_creates_its_target(tmp_path: Path) -> None:
    link = tmp_path / "link.csv"
    link.symlink_to("made.csv")  # relative, as `ln -s made.csv link.csv` makes it
    with atomic_write(link) as handle:  # outside a set, too
        handle.write("new\n")
    assert link.is_symlink() and (tmp_path / "made.csv").read_text() == "new\n"


def test_a_symlink_to_an_input_is_still_refused(tmp_path: Path) -> None:
    route = tmp_path / "route.csv"
    route.write_text("s,z\n")
    (tmp_path / "link.csv").symlink_to(route)
    with pytest.raises(InputError, match="is the input"):
        OutputSet([("-o", str(tmp_path / "link.csv"), True)], inputs=[str(route)])


def test_a_symlink_to_a_folder_is_refused(tmp_path: Path) -> None:
    (tmp_path / "dir").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "dir")
    with pytest.raises(InputError, match="is a folder"):
        OutputSet([("-o", str(tmp_path / "link"), True)])


# --------------------------------------------------------------------------------------
# Item 7: the output folder swapped for a link to the inputs' folder during the run.


def _swap(tmp_path: Path, out: Path, inputs: Path) -> None:
    out.rename(tmp_path / "out.old")  # while the command runs: out/ becomes a link to inputs/
    out.symlink_to(inputs)


@pytest.mark.parametrize("when", ["before the output is written", "after it is written"])
@pytest.mark.parametrize("name", ["route.csv", "other.csv"])
def test_a_folder_swapped_during_the_run_never_replaces_an_input(tmp_path: Path, name: str, when: str) -> None:
    inputs, out = tmp_path / "inputs", tmp_path / "out"
    inputs.mkdir()
    out.mkdir()
    route = inputs / "route.csv"
    route.write_text("the input\n")
    before = sorted(p.name for p in inputs.iterdir())
    output = out / name
    outputs = OutputSet([("-o", str(output), True)], inputs=[str(route)])
    try:
        with outputs:
            if when.startswith("before"):
                _swap(tmp_path, out, inputs)
            with atomic_write(output) as handle:
                handle.write("the output\n")
            if when.startswith("after"):
                _swap(tmp_path, out, inputs)
    except InputError as exc:
        # the same name: now the input itself, refused by identity; another name written
        # through the link: not in the folder that was checked, refused
        assert ("is now the input" in str(exc)) == (name == "route.csv"), exc
        assert "nothing was written" in str(exc)
    else:  # written in the folder that was checked (now out.old), not in the inputs' folder
        assert (name, when) == ("other.csv", "after it is written")
        assert (tmp_path / "out.old" / name).read_text() == "the output\n"
    assert route.read_text() == "the input\n"
    assert sorted(p.name for p in inputs.iterdir()) == before


# --------------------------------------------------------------------------------------
# Pictures: the format follows the extension, and one matplotlib cannot write is refused.


@pytest.mark.parametrize("name, expected", [("a.png", "png"), ("a.JPG", "jpeg"), ("a.jpeg", "jpeg"),
                                            ("a.svg", "svg"), ("a.pdf", "pdf"), ("/dev/null", "png")])
def test_picture_format_follows_the_extension(name: str, expected: str) -> None:
    assert picture_format(name) == expected


def test_every_picture_format_is_one_matplotlib_writes() -> None:
    from matplotlib.backend_bases import FigureCanvasBase

    supported = set(FigureCanvasBase.get_supported_filetypes())
    for ext in ("png", "jpg", "jpeg", "pdf", "svg", "svgz", "eps", "ps", "tif", "tiff", "webp"):
        assert ext in supported
        picture_format(f"a.{ext}")


def test_a_picture_extension_matplotlib_cannot_write_is_refused_before_work(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"--plot .*a\.gif: a picture cannot be written as '\.gif'; end its name"):
        OutputSet([("-o", str(tmp_path / "p.csv"), True), ("--plot", str(tmp_path / "a.gif"))])
    OutputSet([("-o", str(tmp_path / "a.gif"), True)])  # not a picture option: any name


def test_a_jpeg_picture_is_a_jpeg(tmp_path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    path = tmp_path / "plan.jpg"
    with atomic_path(path) as tmp:
        fig = Figure()
        fig.add_subplot().plot([0, 1])
        fig.savefig(tmp, format=picture_format(path))
    assert path.read_bytes()[:3] == b"\xff\xd8\xff"  # the JPEG SOI marker


def test_atomic_write_escapes_what_utf8_cannot_encode(tmp_path) -> None:
    # a file name that is not UTF-8 reaches Python as lone surrogates: written as their escape,
    # never a UnicodeEncodeError once the work is done (issue 30, second round)
    out = tmp_path / "t.csv"
    with atomic_write(out) as handle:
        handle.write(f"# route {os.fsdecode(b'r' + bytes([0xff]) + b'.csv')}\n")
    assert out.read_bytes() == b"# route r\\udcff.csv\n"


def test_a_file_replaced_keeps_its_permissions(tmp_path) -> None:
    # Issue 30 item 6 (written through as shell redirection does): '> out.csv' leaves a 0600
    # file 0600; the output written into it by rename must too.
    import stat

    from profileopt.io.atomic import atomic_write

    out = tmp_path / "out.csv"
    out.write_text("old\n")
    out.chmod(0o600)
    with atomic_write(out) as handle:
        handle.write("new\n")
    assert out.read_text() == "new\n" and stat.S_IMODE(out.stat().st_mode) == 0o600
    fresh = tmp_path / "fresh.csv"
    with atomic_write(fresh) as handle:
        handle.write("x\n")
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o666 & ~_current_umask()


def _current_umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask
