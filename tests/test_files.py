"""A result file is written whole or not at all (herringbone.files.replace_file)."""
import pytest

from herringbone.files import replace_file


def test_a_written_file_replaces_the_one_before(tmp_path):
    target = tmp_path / "table.csv"
    target.write_text("old\n")
    replace_file(target, lambda staging: staging.write_text("new\n"))
    assert target.read_text() == "new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


@pytest.mark.parametrize("stop", [KeyboardInterrupt, OSError])
def test_a_write_stopped_halfway_leaves_the_file_before_and_no_staging(tmp_path, stop):
    target = tmp_path / "table.csv"
    target.write_text("old\n")

    def half(staging):
        staging.write_text("the first half of a ta")
        raise stop

    with pytest.raises(stop):
        replace_file(target, half)
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_the_staging_file_keeps_the_extension_that_writers_read_the_format_from(tmp_path):
    seen = []
    replace_file(tmp_path / "chart.png", lambda staging: seen.append(staging))
    assert seen[0].suffix == ".png" and seen[0].parent == tmp_path
    assert seen[0].name.startswith(".chart.")  # hidden beside the target


def test_a_picture_is_written_through_it(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure = plt.figure()
    replace_file(tmp_path / "chart.pdf", lambda staging: figure.savefig(staging))
    plt.close(figure)
    assert (tmp_path / "chart.pdf").read_bytes().startswith(b"%PDF")
