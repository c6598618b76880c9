"""HDF5 artifacts: provenance attributes, documented datasets, validated reading, atomic writing."""

import json

import h5py
import numpy as np
import pytest

from posefix import __version__
from posefix.io.artifacts import config_hash, inputs_hash, read_artifact, write_artifact
from posefix.io.errors import InputError
from posefix.io.files import file_sha256


def _write(path, inputs, **datasets):
    write_artifact(path, "demo", datasets, params={"b": 2, "a": [1.0]}, inputs=inputs, timings={"read": 0.5},
                   metrics={"count": 3}, docs={"x": ("length", "positions, (2, 3) float64")})


def test_round_trip_with_provenance(tmp_path):
    src = tmp_path / "in.txt"
    src.write_text("input")
    X = np.arange(6.0).reshape(2, 3)
    _write(tmp_path / "a.h5", [src], x=X, names=np.array(["é", "b"]))
    data, attrs = read_artifact(tmp_path / "a.h5", "demo", ["x", "names"])
    assert np.array_equal(data["x"], X) and [n.decode() for n in data["names"]] == ["é", "b"]
    assert attrs["stage"] == "demo" and attrs["posefix_version"] == __version__ and attrs["metrics"] == {"count": 3}
    assert attrs["config_sha256"] == config_hash({"a": [1.0], "b": 2}) == config_hash(json.loads(attrs["config"]))
    assert attrs["inputs_sha256"] == inputs_hash([src]) and inputs_hash([src]) != file_sha256(src)
    with h5py.File(tmp_path / "a.h5", "r") as fh:
        assert fh["x"].attrs["units"] == "length" and fh["timings"].attrs["read"] == 0.5


def test_big_datasets_are_compressed_and_identical_inputs_give_identical_files(tmp_path):
    big = np.zeros((300_000,))
    _write(tmp_path / "a.h5", [], x=big)
    _write(tmp_path / "b.h5", [], x=big)
    with h5py.File(tmp_path / "a.h5", "r") as fh:
        assert fh["x"].compression == "gzip"
    assert (tmp_path / "a.h5").stat().st_size < big.nbytes / 10
    assert (tmp_path / "a.h5").read_bytes() == (tmp_path / "b.h5").read_bytes()


def test_wrong_stage_missing_dataset_and_garbage_are_input_errors(tmp_path):
    _write(tmp_path / "a.h5", [], x=np.zeros(3))
    with pytest.raises(InputError, match="not a 'fit' artifact"):
        read_artifact(tmp_path / "a.h5", "fit", [])
    with pytest.raises(InputError, match="missing dataset"):
        read_artifact(tmp_path / "a.h5", "demo", ["y"])
    (tmp_path / "junk.h5").write_text("not hdf5")
    with pytest.raises(InputError, match="cannot be read as HDF5"):
        read_artifact(tmp_path / "junk.h5", "demo", [])


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    _write(tmp_path / "a.h5", [], x=np.zeros(3))
    before = (tmp_path / "a.h5").read_bytes()
    with pytest.raises(TypeError):
        _write(tmp_path / "a.h5", [], x=np.zeros(3), bad=object())
    assert (tmp_path / "a.h5").read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["a.h5"]
