"""URDF files as a careless user or a hostile file would write them (issue #46, item 5): DTDs
in any encoding, files over the size limit, mimic joints, effort and velocity, URDF's number
grammar, names XML must escape, axis values and nearly parallel axes. Every refusal is one
line naming the file, the element and the rule."""

from __future__ import annotations

import dataclasses

import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from nfarm.infra.reading import ParamsError, ParamsWarning
from nfarm.model import urdf_import
from nfarm.model.robot import load_robot, robot_from_dict, robot_to_dict
from nfarm.model.rotations import log_so3
from nfarm.model.urdf_export import to_urdf
from nfarm.model.urdf_import import from_urdf
from test_urdf import GOOD, check_against_pinocchio


def refused(tmp_path, text: str | bytes, message: str, **kwargs) -> str:
    """``text`` written to a URDF file is refused with one line, starting with the file's
    path, matching ``message``; returns that line."""
    path = tmp_path / "bad.urdf"
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    with pytest.raises(ParamsError, match=message) as caught:
        from_urdf(path, **kwargs)
    line = str(caught.value)
    assert line.startswith(f"{path}: ") and "\n" not in line, line
    return line


def read(tmp_path, text: str | bytes, name: str = "ok.urdf", **kwargs):
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return from_urdf(path, **kwargs)


def same_robot(a, b) -> None:
    for key in ("a", "alpha", "d", "offset", "qlim", "mass", "com", "inertia", "base", "tool",
                "effort", "velocity"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)
    assert a.joint_names == b.joint_names


# -- DTDs and entities, whatever the encoding ----------------------------------------------------


DTD = '<!DOCTYPE robot [<!ENTITY x "boom">]>\n'
WITH_DTD = GOOD.replace('<robot name="two">', DTD + '<robot name="two&x;">')
DECLARED = '<?xml version="1.0" encoding="{}"?>\n'


@pytest.mark.parametrize("encoding, bom", [
    ("utf-8", b""), ("utf-8", b"\xef\xbb\xbf"),
    ("utf-16-le", b"\xff\xfe"), ("utf-16-be", b"\xfe\xff"),   # with their byte-order marks
    ("utf-16-le", b""), ("utf-16-be", b""),                   # and without
    ("utf-32-le", b"\xff\xfe\x00\x00"), ("utf-32-be", b""),
])
def test_a_dtd_is_refused_in_any_unicode_encoding(tmp_path, encoding, bom):
    label = encoding.split("-")[0] + "-" + encoding.split("-")[1]
    for text in (WITH_DTD, DECLARED.format(label.upper()) + WITH_DTD):
        refused(tmp_path, bom + text.encode(encoding), r"<!DOCTYPE>/<!ENTITY> declarations are not accepted")


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be", "utf-32-le"])
def test_the_same_file_in_utf16_or_utf32_reads_as_in_utf8(tmp_path, encoding):
    mark = {"utf-16-le": b"\xff\xfe", "utf-16-be": b"\xfe\xff", "utf-32-le": b"\xff\xfe\x00\x00"}
    text = DECLARED.format(encoding[:6].upper()) + GOOD
    same_robot(read(tmp_path, mark[encoding] + text.encode(encoding)), read(tmp_path, GOOD, "utf8.urdf"))


def test_an_8_bit_encoding_is_decoded_before_the_check(tmp_path):
    """A declared Latin-1 file is read as Latin-1 (its é a name's letter); its DTD is refused;
    encodings that would hide markup from a byte search (UTF-7) or are no text encodings are
    refused by name; bytes not of the declared encoding are one line."""
    latin = (DECLARED.format("ISO-8859-1") + GOOD.replace('name="j1"', 'name="jé"')).encode("latin-1")
    assert read(tmp_path, latin).joint_names == ("jé", "j2")
    refused(tmp_path, (DECLARED.format("latin-1") + WITH_DTD).encode("latin-1"), r"<!DOCTYPE>")
    hidden = DECLARED.format("UTF-7") + GOOD.replace('<robot name="two">', "+ADw-!DOCTYPE robot+AD4-<robot>")
    refused(tmp_path, hidden.encode("ascii"), r"encoding 'UTF-7' \(its XML declaration\) is not read")
    refused(tmp_path, (DECLARED.format("base64") + GOOD).encode(), r"encoding 'base64' .* is not read")
    refused(tmp_path, (DECLARED.format("no-such") + GOOD).encode(), r"encoding 'no-such' .* is not read")
    refused(tmp_path, GOOD.encode().replace(b"two", b"tw\xff"), r"not utf-8 text at byte \d+")
    refused(tmp_path, b"\xff\xfe" + GOOD.encode("utf-16-le")[:-1], r"not utf-16-le text at byte")


def test_an_entity_without_a_doctype_and_a_comment_are_handled(tmp_path):
    refused(tmp_path, GOOD.replace('<robot name="two">', '<robot name="two"><!ENTITY a "b">'),
            r"<!DOCTYPE>/<!ENTITY>")
    refused(tmp_path, GOOD.replace('name="two"', 'name="&x;"'), r"not well-formed XML at line 1")
    # Character references are text, not markup: a name may spell "<!DOCTYPE".
    robot = read(tmp_path, GOOD.replace('name="j1"', 'name="&#60;!DOCTYPE"'))
    assert robot.joint_names[0] == "<!DOCTYPE"


# -- the size limit, before reading -----------------------------------------------------------


def test_the_size_limit_is_checked_before_the_file_is_parsed(tmp_path, monkeypatch):
    big = GOOD.replace("</robot>", "<!--" + "x" * (2 << 20) + "--></robot>")
    monkeypatch.setattr(urdf_import, "parse_urdf", lambda *a: pytest.fail("parsed a file over the limit"))
    refused(tmp_path, big, r"file is \d+ bytes, over the limit of 1048576 for a URDF$")   # parse_urdf never ran
    (tmp_path / "big.urdf").write_text(big)
    (tmp_path / "big.yaml").write_text("name: big\nurdf: big.urdf\n")
    with pytest.raises(ParamsError, match=r"big.urdf: file is \d+ bytes, over the limit of 1048576"):
        load_robot(tmp_path / "big.yaml")       # a robot file naming it: the same line, no parse
    monkeypatch.undo()
    refused(tmp_path, GOOD, r"over the limit of 100 for a URDF", max_bytes=100)
    assert read(tmp_path, big, max_bytes=4 << 20).n == 2      # the limit is a keyword


# -- mimic joints -----------------------------------------------------------------------------


def _jaw(name: str, mimic: str = "", parent: str = "l1", axis: str = "0 1 0") -> str:
    return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{name}_link"/>'
            f'<origin xyz="0.05 0.02 0" rpy="0 0 0"/><axis xyz="{axis}"/>{mimic}'
            f'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
            f'<link name="{name}_link"><inertial><origin xyz="0.03 0 0.01"/><mass value="0.2"/>'
            f'<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial></link>')


MIMIC = '<mimic joint="{}" multiplier="{}" offset="{}"/>'


def test_a_mimic_joint_on_the_chain_is_refused_naming_it_and_its_driver(tmp_path):
    on_chain = GOOD.replace('<axis xyz="0 0 1"/>\n    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>',
                            '<axis xyz="0 0 1"/><mimic joint="j1"/>\n    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>')
    assert on_chain != GOOD
    refused(tmp_path, on_chain, r"joint 'j2': mimics joint 'j1' but lies on the chain: mimic joints "
                                r"on the chain \(one joint driving two\) are not supported")
    driven_by_chain = GOOD.replace("</robot>", _jaw("jaw", MIMIC.format("j1", 1, 0)) + "</robot>")
    refused(tmp_path, driven_by_chain, r"joint 'jaw': mimics joint 'j1', which lies on the chain",
            tip="l2")


def test_a_mimic_joint_off_the_chain_is_locked_at_the_mimics_value(tmp_path):
    """A second jaw mimicking the first (multiplier −1.5, offset 0.1) sits where an explicit lock
    at −1.5 · q + 0.1 puts it, not at 0, and agrees with Pinocchio's own parse locked there;
    a mimic of a mimic follows both."""
    mimic = GOOD.replace("</robot>", _jaw("jaw") + _jaw("jaw2", MIMIC.format("jaw", -1.5, 0.1))
                         + _jaw("jaw3", '<mimic joint="jaw2" multiplier="2"/>', axis="1 0 0") + "</robot>")
    plain = GOOD.replace("</robot>", _jaw("jaw") + _jaw("jaw2") + _jaw("jaw3", axis="1 0 0") + "</robot>")
    for q in (0.0, 0.4):
        robot = read(tmp_path, mimic, "mimic.urdf", tip="l2", lock={"jaw": q})
        jaw2 = -1.5 * q + 0.1
        expected = read(tmp_path, plain, "plain.urdf", tip="l2", lock={"jaw": q, "jaw2": jaw2, "jaw3": 2 * jaw2})
        same_robot(robot, expected)
        check_against_pinocchio(robot, tmp_path / "mimic.urdf", "l2", {"jaw": q, "jaw2": jaw2, "jaw3": 2 * jaw2})
    unlocked = read(tmp_path, plain, "plain.urdf", tip="l2", lock={"jaw": 0.4})
    assert not np.allclose(read(tmp_path, mimic, "mimic.urdf", tip="l2", lock={"jaw": 0.4}).com, unlocked.com)


@pytest.mark.parametrize("jaws, message, lock", [
    (_jaw("jaw", MIMIC.format("nope", 1, 0)), r"joint 'jaw' <mimic joint>: names a joint that does not exist: 'nope'", {}),
    (_jaw("jaw", '<mimic multiplier="2"/>'), r"joint 'jaw' <mimic joint>: is required", {}),
    (_jaw("jaw", MIMIC.format("jaw2", 1, 0)) + _jaw("jaw2", MIMIC.format("jaw", 1, 0)),
     r"joint 'jaw' <mimic joint>: mimic joints drive each other in a loop: jaw → jaw2 → jaw", {}),
    (_jaw("jaw", MIMIC.format("jaw", 1, 0)), r"mimic joints drive each other in a loop: jaw → jaw", {}),
    (_jaw("jaw") + _jaw("jaw2", MIMIC.format("jaw", 1, 0)),
     r"lock.jaw2: joint 'jaw2' mimics joint 'jaw': it follows that joint; lock that one instead", {"jaw2": 0.3}),
    (_jaw("jaw") + _jaw("jaw2", MIMIC.format("jaw", "1e300", 0)) + _jaw("jaw3", MIMIC.format("jaw2", "1e300", 0)),
     r"joint 'jaw3' <mimic>: its position 1e\+300 · 1e\+300 \+ 0.0 is not finite", {"jaw": 1.0}),
    (_jaw("jaw", MIMIC.format("j1", "two", 0)), r"joint 'jaw' <mimic multiplier>: must be a finite number", {}),
    (_jaw("jaw", MIMIC.format("jaw0", 1, 0)) + '<joint name="jaw0" type="fixed"><parent link="l1"/>'
     '<child link="jaw0_link"/></joint><link name="jaw0_link"/>',
     r"joint 'jaw' <mimic joint>: names joint 'jaw0' of type 'fixed', which does not move", {}),
    ('<joint name="jaw" type="fixed"><parent link="l1"/><child link="jaw_link"/><mimic joint="j1"/>'
     '</joint><link name="jaw_link"/>', r"joint 'jaw' <mimic>: a 'fixed' joint cannot mimic another", {}),
])
def test_every_mimic_rule_has_a_bad_file(tmp_path, jaws, message, lock):
    refused(tmp_path, GOOD.replace("</robot>", jaws + "</robot>"), message, tip="l2", lock=lock)


# -- effort and velocity ----------------------------------------------------------------------


@pytest.mark.parametrize("key, value", [("effort", "-2"), ("velocity", "-3"), ("effort", "-1e-300")])
def test_a_negative_effort_or_velocity_is_refused(tmp_path, key, value):
    bad = GOOD.replace(f'{key}="{2 if key == "effort" else 3}"', f'{key}="{value}"', 1)
    refused(tmp_path, bad, rf"joint 'j1' <limit {key}>: must be > 0 \(or 0 for no limit\), got '{value}'")


def test_an_effort_of_zero_means_none_as_to_urdf_writes_it(tmp_path, intelbot5):
    robot = read(tmp_path, GOOD.replace('effort="2"', 'effort="0"', 1))
    assert robot.effort.tolist() == [np.inf, 2.0]
    assert 'effort="0" velocity="0"' in to_urdf(intelbot5)          # intelbot5 gives none
    again = read(tmp_path, to_urdf(intelbot5), "intelbot5.urdf", tip="tool")
    assert np.isinf(again.effort).all() and np.isinf(again.velocity).all()


# -- URDF's number grammar --------------------------------------------------------------------


@pytest.mark.parametrize("bad", ["0.2_0", "０.２", "٠.2", "inf", "-Infinity", "nan", "0x10", "1e",
                                 ".", "+-1", "1.0f", "1,5", "1e5.5", "--1", "２"])
def test_numbers_follow_urdfs_grammar(tmp_path, bad):
    line = refused(tmp_path, GOOD.replace('xyz="0.2 0 0"', f'xyz="{bad} 0 0"'),
                   r"joint 'j2' <origin xyz>: must be 3 finite numbers, got .* is not a plain decimal number")
    assert repr(bad) in line
    refused(tmp_path, GOOD.replace('<mass value="0.5"/>', f'<mass value="{bad}"/>'),
            r"link 'l1' <inertial><mass value>: must be a finite number, got .* not a plain decimal")
    refused(tmp_path, GOOD.replace('lower="-1"', f'lower="{bad}"', 1),
            r"joint 'j1' <limit lower>: must be a finite number")


def test_numbers_are_separated_by_xml_white_space_only(tmp_path):
    for separator in ("\u00a0", "\u2003", "\u3000"):
        refused(tmp_path, GOOD.replace('xyz="0.2 0 0"', f'xyz="0.2{separator}0 0"'),
                r"joint 'j2' <origin xyz>: must be 3 finite numbers")
    refused(tmp_path, GOOD.replace('xyz="0.2 0 0"', 'xyz="1e400 0 0"'),
            r"joint 'j2' <origin xyz>: must be 3 finite numbers, got '1e400 0 0'$")
    refused(tmp_path, GOOD.replace('xyz="0.2 0 0"', 'xyz=""'), r"<origin xyz>: must be 3 finite numbers, got ''$")
    line = refused(tmp_path, GOOD.replace('xyz="0.2 0 0"', f'xyz="{"1 " * 10_000}"'),
                   r"<origin xyz>: must be 3 finite numbers, got '1 1 1 ")
    assert len(line) < len(str(tmp_path)) + 120                     # a short repr of the text


def test_plain_decimal_numbers_of_every_form_are_read(tmp_path):
    spelled = GOOD.replace('xyz="0.2 0 0"', 'xyz="\t+.2E0\n 0. -0 "').replace('<mass value="0.5"/>', '<mass value="5e-1"/>')
    same_robot(read(tmp_path, spelled, "spelled.urdf"), read(tmp_path, GOOD))


# -- names XML must escape --------------------------------------------------------------------


NAMES = ['a&b', 'x<y>z', 'say "hi"', "it's", 'tab\tnew\nline', '&amp;', ']]>', 'ünï']


def test_names_with_xml_characters_are_escaped_and_read_back(tmp_path):
    robot = read(tmp_path, GOOD)
    for name in NAMES:
        # a robot file's name is a plain file name (robot.py's ROBOT_NAME); a URDF's is any text
        named = dataclasses.replace(robot_from_dict({**robot_to_dict(robot), "name": "named",
                                                     "joints": [{**j, "name": name + str(i)} for i, j in
                                                                enumerate(robot_to_dict(robot)["joints"])]}),
                                    name=name)
        for prefix in ("", "p&<\"'_"):
            text = to_urdf(named, prefix=prefix)
            root = ET.fromstring(text)                             # well-formed
            assert root.get("name") == prefix + name
            revolute = [j.get("name") for j in root.iter("joint") if j.get("type") == "revolute"]
            assert revolute == [prefix + name + "0", prefix + name + "1"]
            # such a <robot name> cannot name directories: read back under a robot name (a robot
            # file's or add-arm's), refused without one (tests/test_hardening4.py)
            (tmp_path / "named.urdf").write_text(text)
            again = from_urdf(tmp_path / "named.urdf", tip=prefix + "tool", name="again")
            assert again.name == "again" and again.joint_names == tuple(revolute)
            with pytest.raises(ParamsError, match=r"<robot name>: must be 1-64 letters"):
                read(tmp_path, text, "named.urdf", tip=prefix + "tool")
            np.testing.assert_allclose(again.a, robot.a, atol=1e-12)


def test_a_name_xml_cannot_hold_is_one_line(tmp_path):
    robot = read(tmp_path, GOOD)
    data = robot_to_dict(robot)
    data["joints"][1]["name"] = "bell\x07"
    with pytest.raises(ParamsError, match=r"joints\[1\]\.name: 'bell\\x07' holds U\+0007, which XML "
                                          r"cannot hold: the robot cannot be written as a URDF$"):
        to_urdf(robot_from_dict(data, source="x.yaml"))
    with pytest.raises(ParamsError, match=r"^to_urdf: prefix: .* holds U\+0000"):
        to_urdf(robot, prefix="\x00")


# -- axes ---------------------------------------------------------------------------------------


J2_AXIS = '<axis xyz="0 0 1"/>\n    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>'


def _axis(text: str) -> str:
    assert GOOD.count(J2_AXIS) == 1
    return GOOD.replace(J2_AXIS, J2_AXIS.replace('"0 0 1"', f'"{text}"'))


@pytest.mark.parametrize("axis, message", [
    ("1e300 1e300 0", r"its length overflows, got '1e300 1e300 0': give a direction of moderate size"),
    ("1e200 -1e200 1e200", r"its length overflows"),
    ("0 0 0", r"must not be the zero vector \(length below 1e-12\), got '0 0 0'"),
    ("1e-13 0 0", r"must not be the zero vector"),
    ("1e-300 1e-300 0", r"must not be the zero vector"),
    ("nan 0 1", r"must be 3 finite numbers, got 'nan 0 1': 'nan' is not a plain decimal number"),
    ("1e999 0 0", r"must be 3 finite numbers, got '1e999 0 0'$"),
    ("0 1", r"must be 3 finite numbers, got '0 1'$"),
])
def test_axis_values_are_validated(tmp_path, axis, message):
    refused(tmp_path, _axis(axis), r"joint 'j2' <axis xyz>: " + message)


def test_a_large_or_small_but_sound_axis_is_a_direction(tmp_path):
    same_robot(read(tmp_path, _axis("0 0 1e150"), "big.urdf"), read(tmp_path, GOOD))
    same_robot(read(tmp_path, _axis("0 0 1e-6"), "small.urdf"), read(tmp_path, GOOD))


# -- nearly parallel axes -------------------------------------------------------------------------


PARALLEL = """<robot name="pitch">
  <link name="base"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="2" velocity="3"/></joint>
  <link name="upper"/>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0 0 0.3" rpy="{tilt} 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>
  <link name="fore"><inertial><origin xyz="0 0 0.1"/><mass value="0.5"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="wrist" type="revolute"><parent link="fore"/><child link="hand"/>
    <origin xyz="0 0 0.25"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="2" velocity="3"/></joint>
  <link name="hand"/>
</robot>
"""


@pytest.mark.parametrize("tilt", [3.1416 - np.pi, 1.5708 - np.pi / 2, 1e-3, -2e-2])
def test_nearly_parallel_axes_are_converted_exactly_and_named_in_one_line(tmp_path, tilt):
    """Pitch axes a rounded π apart (a CAD export writes 3.1416) have their common normal
    kilometres away: the pair is written as parallel DH axes with the tilt in a fixed transform
    after the row, so the DH table stays at the arm's size and the robot is Pinocchio's own parse
    of the file to 1e-10; one warning names the joints, the angle and where the tilt went."""
    text = PARALLEL.format(tilt=tilt)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = read(tmp_path, text, "tilted.urdf")
    messages = [str(w.message) for w in caught if issubclass(w.category, ParamsWarning)]
    assert len(messages) == 1, messages
    assert messages[0].startswith(f"{tmp_path / 'tilted.urdf'}: joints 'shoulder' and 'elbow': "
                                  f"axes nearly parallel, {abs(np.degrees(tilt)):.3g}° apart: "
                                  f"written as parallel DH axes with the tilt in joints[0].fixed ")
    assert "millimetres" not in messages[0] and "\n" not in messages[0]
    assert caught[0].filename == __file__                      # pointing at the caller
    assert np.abs(robot.a).max() < 1 and np.abs(robot.d).max() < 1          # [m]
    assert robot.alpha[0] == 0.0 and robot.fixed is not None
    E = robot.fixed[0]
    np.testing.assert_allclose(np.linalg.norm(log_so3(E[:3, :3])), abs(tilt), rtol=1e-6)
    np.testing.assert_array_equal(robot.fixed[1:], np.broadcast_to(np.eye(4), (2, 4, 4)))
    check_against_pinocchio(robot, tmp_path / "tilted.urdf", "hand", {})
    again = robot_from_dict(robot_to_dict(robot))                # the robot file holds it
    np.testing.assert_array_equal(again.fixed, robot.fixed)


def test_parallel_and_clearly_skew_axes_need_no_fixed_transform(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for tilt in (0, 1e-13, 0.3):                   # parallel, parallel to rounding, skew
            robot = read(tmp_path, PARALLEL.format(tilt=tilt), "plain.urdf")
            assert robot.fixed is None
            check_against_pinocchio(robot, tmp_path / "plain.urdf", "hand", {})


def test_the_bound_on_nearly_parallel_axes_is_a_keyword(tmp_path):
    """Below ``near_parallel_deg`` only: with a bound under the tilt, the pair is plain DH, its
    common normal kilometres away (a length in millimetres? warns) and still exact."""
    tilt = 3.1416 - np.pi
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = read(tmp_path, PARALLEL.format(tilt=tilt), "tilted.urdf", near_parallel_deg=1e-4)
    assert {"millimetres?" in str(w.message) for w in caught} == {True}
    assert robot.fixed is None and np.abs(robot.d).max() > 1000
    check_against_pinocchio(robot, tmp_path / "tilted.urdf", "hand", {})   # the normal found exactly


def test_a_length_in_millimetres_still_warns_where_axes_are_not_nearly_parallel(tmp_path):
    mm = PARALLEL.format(tilt=0).replace('xyz="0 0 0.25"', 'xyz="0 0 250"')
    with pytest.warns(ParamsWarning, match=r"m is over 10 m: a length in millimetres\?"):
        read(tmp_path, mm, "mm.urdf")


def test_a_strange_declared_encoding_is_one_short_line(tmp_path):
    for name in ("a\x01b", "x" * 5000, "utf-8-sig\x7f"):
        line = refused(tmp_path, (DECLARED.format(name) + GOOD).encode("latin-1"), r"encoding .* is not read")
        assert len(line) < len(str(tmp_path)) + 160
