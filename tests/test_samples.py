"""``medax samples``: the packaged samples are listed, copied out whole, never over a file."""

import pytest

from medax.cli.main import main
from medax.errors import InputError
from medax.samples import SAMPLES, copy_samples, sample_path


def test_list_names_every_sample(capsys):
    assert main(["samples"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in SAMPLES)


def test_copy_all_into_a_new_folder(tmp_path, capsys):
    dest = tmp_path / "new" / "samples"
    assert main(["samples", "--all", "-d", str(dest)]) == 0
    assert sorted(p.name for p in dest.iterdir()) == sorted(SAMPLES)
    for name in SAMPLES:
        assert (dest / name).read_bytes() == sample_path(name).read_bytes()
    assert capsys.readouterr().out.count("wrote ") == len(SAMPLES)


def test_copy_one(tmp_path):
    assert main(["samples", "l-bracket.step", "-d", str(tmp_path)]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["l-bracket.step"]


def test_existing_file_is_never_overwritten_and_nothing_is_copied(tmp_path, capsys):
    (tmp_path / "regions.json").write_text("mine")
    assert main(["samples", "--all", "-d", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "regions.json: already there; nothing copied" in err and err.count("\n") == 1
    assert [p.name for p in tmp_path.iterdir()] == ["regions.json"]
    assert (tmp_path / "regions.json").read_text() == "mine"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["samples", "nope.step"], "no sample named 'nope.step' (samples: regions.json"),
        (["samples", "regions.json", "--all"], "give sample names or --all, not both"),
    ],
)
def test_refusals_are_one_line(tmp_path, capsys, argv, message):
    assert main([*argv, "-d", str(tmp_path)]) == 1
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_file_as_folder_is_refused(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(InputError, match="exists and is not a folder"):
        copy_samples(["regions.json"], tmp_path / "f")
    with pytest.raises(InputError, match="name at least one sample"):
        copy_samples([], tmp_path)


def test_step_samples_are_the_catalogue_parts():
    """The shipped STEP files read back as the catalogue's parts: faces and volume."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from medax.cad import parts as catalogue
    from medax.cad.reader import read_part
    from medax.cad.simplify import parts
    from medax.cad.simplify.occ import faces_of

    def volume(shape):
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(shape, props)
        return props.Mass()

    built = {
        "box-12-edges.step": parts.box_all_fillets(),
        "filleted-boss.step": catalogue.plate_with_boss(),
        "l-bracket.step": catalogue.l_bracket(),
    }
    for name, part in built.items():
        (solid,) = read_part(sample_path(name)).solids
        assert len(list(faces_of(solid))) == len(list(faces_of(part.shape))), name
        assert volume(solid) == pytest.approx(volume(part.shape), rel=1e-9), name
