"""What a user of an installed bhgrasp meets: a checkout that shadows the install, committed results kept safe."""

from __future__ import annotations

import json
from importlib import metadata
from pathlib import Path

import pytest

from bhgrasp import _native
from bhgrasp.cli import main
from bhgrasp.thesis import results


def _installed_layout(root: Path, with_package: bool) -> metadata.Distribution:
    """site-packages with bhgrasp's extension (and, for a wheel, its __init__.py) and the dist-info that lists them."""
    site = root / "site-packages"
    (site / "bhgrasp").mkdir(parents=True)
    (site / "bhgrasp" / "_core.cpython-311-x86_64-linux-gnu.so").write_bytes(b"")
    files = ["bhgrasp/_core.cpython-311-x86_64-linux-gnu.so,,"]
    if with_package:
        (site / "bhgrasp" / "__init__.py").write_text("")
        files.append("bhgrasp/__init__.py,,")
    info = site / "bhgrasp-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: bhgrasp\nVersion: 0.1.0\n")
    (info / "RECORD").write_text("\n".join(files) + "\n")
    return metadata.PathDistribution(info)


def _checkout(root: Path) -> Path:
    (root / "checkout" / "bhgrasp").mkdir(parents=True)
    (root / "checkout" / "pyproject.toml").write_text("[project]\nname = 'bhgrasp'\n")
    return root / "checkout" / "bhgrasp"


def test_a_checkout_that_shadows_a_wheel_is_named(tmp_path: Path) -> None:
    """`pip install .`, then Python started in the checkout: the error names both folders and the cure."""
    wheel = _installed_layout(tmp_path, with_package=True)
    found = _native._shadowed_install(_checkout(tmp_path), wheel)
    assert found == (tmp_path / "site-packages" / "bhgrasp").resolve()


def test_an_editable_install_or_an_installed_package_shadows_nothing(tmp_path: Path) -> None:
    editable = _installed_layout(tmp_path, with_package=False)  # site-packages holds only the extension
    assert _native._shadowed_install(_checkout(tmp_path), editable) is None
    installed = tmp_path / "site-packages" / "bhgrasp"  # the package imported is the installed one itself
    assert _native._shadowed_install(installed, _installed_layout(tmp_path / "other", with_package=True)) is None


def test_the_message_of_a_shadowed_install(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import builtins

    real_import = builtins.__import__

    def no_core(name: str, globals=None, locals=None, fromlist=(), level=0):
        if name == "bhgrasp._core" or (name == "bhgrasp" and fromlist and "_core" in fromlist):
            raise ImportError("No module named 'bhgrasp._core'")
        return real_import(name, globals, locals, fromlist, level)

    monkeypatch.setattr(builtins, "__import__", no_core)
    monkeypatch.setattr(_native, "_shadowed_install", lambda: tmp_path / "site-packages" / "bhgrasp")
    with pytest.raises(_native.CompiledEngineUnavailable) as caught:
        _native.required_core("the compiled engine")
    message = str(caught.value)
    assert "from the source folder" in message and str(tmp_path / "site-packages" / "bhgrasp") in message
    assert "run from another folder, or install this checkout in place with `pip install -e .`" in message


def test_experiments_write_to_a_fresh_folder_and_never_over_committed_results(
    tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    argv = ["experiments", "ch3", "--scale", "0.05", "--no-figures"]
    assert main(argv) == 0
    written = tmp_path / "bhgrasp_experiments" / "chapter3.json"
    assert json.loads(written.read_text())["chapter"] == 3
    before = written.read_bytes()
    capsys.readouterr()
    assert main(argv) == 2  # a folder holding chapter3.json: refused, nothing run, nothing written
    err = capsys.readouterr().err
    assert f"{Path('bhgrasp_experiments') / 'chapter3.json'} already exist(s)" in err and "--force" in err
    assert written.read_bytes() == before
    assert main([*argv, "--force"]) == 0


def test_the_committed_results_are_found_in_a_checkout_and_in_a_wheel(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert results.REFERENCE == results.REPOSITORY / "docs" / "results"
    assert (results.REFERENCE / "chapter5.json").is_file()
    monkeypatch.setattr(results, "REPOSITORY", tmp_path)  # a wheel: no docs/ beside the package
    assert results._reference_folder() == Path(results.__file__).resolve().parents[1] / "results"
    cmake = Path(__file__).parents[1] / "CMakeLists.txt"  # what puts them there
    assert "install(DIRECTORY docs/results/ DESTINATION bhgrasp/results" in cmake.read_text()
