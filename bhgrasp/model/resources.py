"""Where robot descriptions live: the packaged Barrett URDF, example-robot-data, and safe URDF reading."""

from __future__ import annotations

import sys
from pathlib import Path
from xml.etree.ElementTree import Element, ParseError

from defusedxml import DefusedXmlException
from defusedxml.ElementTree import fromstring as safe_fromstring

from bhgrasp.errors import ModelError

_PACKAGE_DIR = Path(__file__).resolve().parents[1]  # the bhgrasp folder
_ERD_SUBDIR = Path("share", "example-robot-data", "robots")


def barrett_urdf_path() -> Path:
    """Path of the packaged BH8-280 URDF.

    A wheel ships it as ``bhgrasp/urdf/barrett_hand.urdf``; an editable install or a source checkout finds the
    top-level ``urdf/barrett_hand.urdf`` beside the package.
    """
    for candidate in (_PACKAGE_DIR / "urdf", _PACKAGE_DIR.parent / "urdf"):
        path = candidate / "barrett_hand.urdf"
        if path.is_file():
            return path
    raise ModelError(f"packaged Barrett URDF not found under {_PACKAGE_DIR} or {_PACKAGE_DIR.parent / 'urdf'}")


def example_robot_data_dir() -> Path:
    """The ``robots`` folder that example-robot-data (>= 6) installs under ``<prefix>/share``.

    example-robot-data 6 ships no Python module: its URDFs sit in ``site-packages/cmeel.prefix/share/...`` for a
    pip install, or in ``<sys.prefix>/share/...`` for a conda or system install.

    Raises:
        ModelError: If example-robot-data is not installed.
    """
    prefixes = [Path(entry) / "cmeel.prefix" for entry in sys.path if entry]
    prefixes += [Path(sys.prefix), Path(sys.base_prefix)]
    for prefix in prefixes:
        robots = prefix / _ERD_SUBDIR
        if robots.is_dir():
            return robots
    raise ModelError(
        "example-robot-data is not installed: it holds the other hands (e.g. the Allegro) and is an optional extra "
        "of bhgrasp (414 MB); `pip install 'bhgrasp[hands]'` or `pip install example-robot-data`"
    )


def example_robot_data_urdf(relative_path: str) -> Path:
    """Absolute path of a URDF of example-robot-data.

    Args:
        relative_path: Path below the ``robots`` folder, e.g.
            ``"allegro_hand_description/urdf/allegro_right_hand.urdf"``.
    """
    path = example_robot_data_dir() / relative_path
    if not path.is_file():
        raise ModelError(f"no file {relative_path!r} in example-robot-data at {example_robot_data_dir()}")
    return path


def read_urdf(path: str | Path) -> tuple[str, Element]:
    """Read a URDF file safely: no DTDs, no entity expansion, no network access.

    Returns:
        The file's text (to hand to Pinocchio) and its parsed root ``<robot>`` element.

    Raises:
        ModelError: If the file is missing, is not UTF-8, is not well-formed XML, declares a DTD/entities, or is
            not a URDF.
    """
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"URDF file not found: {str(path)!r}")
    data = path.read_bytes()
    try:
        text = data.decode("utf-8", errors="strict")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        raise ModelError(
            f"URDF {str(path)!r} is not UTF-8 text: byte 0x{data[error.start]:02x} at offset {error.start} "
            f"(line {line}) is invalid UTF-8 ({error.reason}); save the file as UTF-8"
        ) from error
    try:
        root = safe_fromstring(text, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    except DefusedXmlException as error:
        raise ModelError(
            f"URDF {str(path)!r} declares a DTD or XML entities ({type(error).__name__}); bhgrasp refuses to "
            "expand or fetch them: remove the <!DOCTYPE>/<!ENTITY> declarations"
        ) from error
    except ParseError as error:
        raise ModelError(f"URDF {str(path)!r} is not well-formed XML: {error}") from error
    if root.tag != "robot":
        raise ModelError(f"URDF {str(path)!r} must have a <robot> root element, got <{root.tag}>")
    return text, root


def leaf_links(root: Element) -> list[str]:
    """The fingertips of a hand: links that are the parent of no joint and hang below at least one moving joint.

    In file order.  A leaf fixed rigidly to the base (a palm pad, a camera mount) is not a fingertip.
    """
    joints = [
        joint for joint in root.iter("joint") if joint.find("parent") is not None and joint.find("child") is not None
    ]
    parent_joint = {joint.find("child").get("link"): joint for joint in joints}
    parents = {joint.find("parent").get("link") for joint in joints}

    def moves(link: str) -> bool:
        seen = set()
        while link in parent_joint and link not in seen:  # up to the root (a cycle would be a broken URDF)
            seen.add(link)
            joint = parent_joint[link]
            if joint.get("type") != "fixed":
                return True
            link = joint.find("parent").get("link")
        return False

    return [
        link.get("name")
        for link in root.iter("link")
        if link.get("name") not in parents and link.get("name") in parent_joint and moves(link.get("name"))
    ]
