"""``shc export bag``: every format written and read back, the batch serialiser against the library's, and the
mcap file read by an independent reader."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np
import pytest

from shc_cli.interop.bag import Messages, _serialize_as, _topics, typestore_for
from shc_cli.interop.batch import BatchSerializer
from shc_cli.record.runread import RunLog, read_run

from .test_cli import run


@pytest.fixture(scope="module")
def walked(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shc_cli import simulate

    out = tmp_path_factory.mktemp("bag") / "walk"
    return simulate("bullet", gait="tripod", duration=1.0, out=out, plots=False).path


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shc_cli.commands.plan import run_plan

    return run_plan("bullet", "tripod", "1,0,-0.2", 1.0, None, tmp_path_factory.mktemp("bag") / "plan", False)


@pytest.mark.parametrize("fmt", ["mcap", "ros1"])
def test_batch_bytes_equal_the_librarys_serialiser(walked: Path, fmt: str) -> None:
    """For every topic, rows written by the sentinel template equal serialising the message directly."""
    log = read_run(walked)
    store = typestore_for(fmt)
    serialize = store.serialize_ros1 if fmt == "ros1" else store.serialize_cdr
    stamps = np.round(log.t * 1e9).astype(np.int64)
    for topic, msgtype, build, width, values, once in _topics(log, Messages(store)):
        if once:
            continue
        rows = BatchSerializer(partial(_serialize_as, serialize, msgtype), build, width).serialize(stamps, values)
        for row in (0, len(stamps) // 2, len(stamps) - 1):
            sec, nanosec = divmod(int(stamps[row]), 1_000_000_000)
            direct = bytes(serialize(build(sec, nanosec, values[row].copy()), msgtype))
            assert rows[row].tobytes() == direct, topic


def _read(path: Path, fmt: str) -> dict[str, list[tuple[int, object]]]:
    from shc_cli.interop.bag import read_topics

    topics = read_topics(path)
    assert path.is_file() == (fmt == "ros1")
    return topics


def _check_fields(log: RunLog, topics: dict[str, list[tuple[int, object]]]) -> None:
    from shc_cli.backends.pybullet_.urdf import robot_urdf

    n = len(log.t)
    stamps = np.round(log.t * 1e9).astype(np.int64)
    joint_states = topics["/joint_states"]
    assert len(joint_states) == n and [s for s, _ in joint_states] == stamps.tolist()
    positions = np.array([m.position for _, m in joint_states])  # type: ignore[attr-defined]
    np.testing.assert_array_equal(positions, log.joints.reshape(n, -1))
    assert joint_states[0][1].name[:2] == ["AR_coxa_joint", "AR_coxat_joint"]  # type: ignore[attr-defined]
    truth = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]  # type: ignore[attr-defined]
                      for _, m in topics["/ground_truth/odom"]])
    np.testing.assert_array_equal(truth, log.position)
    odom = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]  # type: ignore[attr-defined]
                     for _, m in topics["/odom"]])  # the leg odometry, at the body's height
    assert log.odometry is not None
    np.testing.assert_array_equal(odom, np.column_stack([log.odometry[:, :2], log.position[:, 2]]))
    assert topics["/robot_description"][0][1].data == robot_urdf(log.robot)  # type: ignore[attr-defined]
    tf = topics["/tf"][n // 2][1]
    assert len(tf.transforms) == 1 + 6 * (5 + 1)  # type: ignore[attr-defined]
    assert tf.transforms[0].header.frame_id == "odom"  # type: ignore[attr-defined]
    foot = next(t for t in tf.transforms if t.child_frame_id == "AR_foot")  # type: ignore[attr-defined]
    state = topics["/shc/AR/state"][n // 2][1]
    assert state.name == "AR"  # type: ignore[attr-defined]
    actual = state.actual_tip_pose.pose.position  # type: ignore[attr-defined]
    # the foot frame in /tf is the tip of the measured joints, as LegState's actual tip
    assert (foot.transform.translation.x, foot.transform.translation.y, foot.transform.translation.z) == \
        pytest.approx((actual.x, actual.y, actual.z), abs=1e-12)
    np.testing.assert_array_equal(state.joint_positions, log.joints[n // 2, 0])  # type: ignore[attr-defined]


@pytest.mark.parametrize("fmt", ["mcap", "sqlite3", "ros1"])
def test_every_format_reads_back(walked: Path, tmp_path: Path, fmt: str, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / ("walk.bag" if fmt == "ros1" else "walk_bag")
    code, stdout, err = run(["export", "bag", str(walked), "--format", fmt, "--out", str(out)], capsys, monkeypatch)
    assert code == 0 and str(out) in stdout, err
    log = read_run(walked)
    topics = _read(out, fmt)
    _check_fields(log, topics)
    power = np.array([m.data for _, m in topics["/shc/power"]])  # type: ignore[attr-defined]
    np.testing.assert_array_equal(power, log.power)
    assert log.foot_force is not None
    forces = np.array([m.wrench.force.z for _, m in topics["/CL/foot_force"]])  # type: ignore[attr-defined]
    np.testing.assert_array_equal(forces, log.foot_force[:, 3])


def test_a_plan_run_exports_its_tip_stages(planned: Path, tmp_path: Path) -> None:
    from shc_cli.interop.bag import export_bag

    log = read_run(planned)
    out = export_bag(log, tmp_path / "plan_bag", "mcap")
    topics = _read(out, "mcap")
    _check_fields(log, topics)
    assert log.tips is not None and log.progress is not None
    last = topics["/shc/BL/state"][-1][1]
    walker = last.walker_tip_pose.pose.position  # type: ignore[attr-defined]
    np.testing.assert_array_equal([walker.x, walker.y, walker.z], log.tips[-1, 4, 0])
    assert last.stance_progress == log.progress[-1, 4, 0]  # type: ignore[attr-defined]


def test_mcap_is_readable_by_the_mcap_library(walked: Path, tmp_path: Path) -> None:
    """An independent reader (mcap + mcap-ros2-support) decodes our bag with the schemas in it."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from shc_cli.interop.bag import export_bag

    log = read_run(walked)
    out = export_bag(log, tmp_path / "walk_bag", "mcap")
    files = sorted(out.glob("*.mcap"))
    assert len(files) == 1
    seen: dict[str, int] = {}
    with files[0].open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages(topics=["/joint_states", "/shc/AR/state"]):
            row = seen.get(channel.topic, 0)
            if channel.topic == "/joint_states":
                np.testing.assert_array_equal(decoded.position, log.joints[row].reshape(-1))
                assert message.log_time == round(log.t[row] * 1e9)
            else:
                np.testing.assert_array_equal(decoded.joint_positions, log.joints[row, 0])
            seen[channel.topic] = row + 1
    assert seen == {"/joint_states": len(log.t), "/shc/AR/state": len(log.t)}


def test_bad_export_requests_are_one_line(walked: Path, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err = run(["export", "bag", str(walked), "--format", "zip", "--out", str(tmp_path / "x")], capsys,
                       monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "'zip' is not a bag format" in err
    (tmp_path / "taken").mkdir()
    code, _, err = run(["export", "bag", str(walked), "--out", str(tmp_path / "taken")], capsys, monkeypatch)
    assert code == 2 and "already exists" in err


METRICS = ("cot", "mean_power_w", "mean_speed_mps", "steady_speed_mps", "commanded_speed_mps", "speed_ratio",
           "distance_m", "duty_factor", "foot_slip_m", "stability_margin_median_m", "stability_margin_min_m",
           "zmp_margin_median_m", "zmp_centre_distance_median_m", "height_median_m", "height_iqr_m",
           "roll_rate_median_rps", "pitch_rate_median_rps", "gait_cycles", "window_s")


@pytest.mark.parametrize(("fixture", "fmt"), [("walked", "mcap"), ("walked", "sqlite3"), ("walked", "ros1"),
                                              ("planned", "mcap")])
def test_analyze_reads_a_bag_as_the_run(fixture: str, fmt: str, tmp_path: Path, request: pytest.FixtureRequest,
                                        capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """Round trip: `shc analyze` of the exported bag gives the run directory's numbers."""
    import json

    from shc_cli.analysis.metrics import analyze_run
    from shc_cli.interop.bag import export_bag

    path: Path = request.getfixturevalue(fixture)
    capsys.readouterr()  # the fixture may have just printed its run's line
    bag = export_bag(read_run(path), tmp_path / ("run.bag" if fmt == "ros1" else "run_bag"), fmt)
    direct = analyze_run(read_run(path))
    code, out, err = run(["analyze", str(bag), "--json"], capsys, monkeypatch)
    assert code == 0, err
    via_bag = json.loads(out)
    assert via_bag["kind"] == direct["kind"]
    for key in METRICS:
        if direct[key] is None:
            assert via_bag[key] is None, key
        else:
            assert via_bag[key] == pytest.approx(direct[key], rel=1e-9, abs=1e-12), key


def test_plan_writes_its_bag_with_bag_option(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "run"
    code, stdout, err = run(["plan", "--duration", "1", "--no-plots", "--out", str(out), "--bag", "ros1"], capsys,
                            monkeypatch)
    assert code == 0, err
    assert (out / "run.bag").is_file() and f"wrote {out / 'run.bag'}" in stdout
    assert not list(tmp_path.glob(".*partial*")) and not list(out.glob(".*partial*"))
    topics = _read(out / "run.bag", "ros1")
    assert len(topics["/joint_states"]) == len(read_run(out).t)
    code, _, err = run(["plan", "--out", str(tmp_path / "other"), "--bag", "zip"], capsys, monkeypatch)
    assert code == 2 and "--bag: 'zip' is not a bag format" in err and not (tmp_path / "other").exists()


@pytest.mark.parametrize("fmt", ["mcap", "sqlite3", "ros1"])
def test_every_field_of_every_topic_is_the_runs(walked: Path, tmp_path: Path, fmt: str) -> None:
    """Every 40th cycle of every topic, as stored in the bag, equals the message built directly from the run's
    numbers and serialised by rosbags: all fields, byte for byte."""
    from shc_cli.interop.bag import export_bag

    log = read_run(walked)
    out = export_bag(log, tmp_path / ("walk.bag" if fmt == "ros1" else "walk_bag"), fmt)
    store = typestore_for(fmt)
    serialize = store.serialize_ros1 if fmt == "ros1" else store.serialize_cdr
    stamps = np.round(log.t * 1e9).astype(np.int64)
    expected = {topic: (msgtype, build, values, once) for topic, msgtype, build, _, values, once
                in _topics(log, Messages(store))}
    raw: dict[str, list[bytes]] = {}
    if fmt == "ros1":
        from rosbags.rosbag1 import Reader as Reader1

        with Reader1(out) as reader:
            for connection, _, data in reader.messages():
                raw.setdefault(connection.topic, []).append(bytes(data))
    else:
        from rosbags.rosbag2 import Reader

        with Reader(out) as reader:
            for connection, _, data in reader.messages():
                raw.setdefault(connection.topic, []).append(bytes(data))
    assert set(raw) == set(expected)
    for topic, (msgtype, build, values, once) in expected.items():
        rows = [0] if once else range(0, len(stamps), 40)
        for row in rows:
            sec, nanosec = (0, 0) if once else divmod(int(stamps[row]), 1_000_000_000)
            direct = bytes(serialize(build(sec, nanosec, values[row].copy() if len(values[row]) else values[row]),
                                     msgtype))
            assert raw[topic][row] == direct, (topic, row)


def test_a_robot_with_a_servo_map_is_exported_with_its_own_joint_names(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The imported PhantomX's [hardware.servos] names each joint as its URDF does (j_c1_rf, …): the bag's
    /joint_states, /desired_joint_states and /robot_description use those names (as the robot's own driver would
    publish them), and /shc/servo_map ties each to its servo id."""
    import json
    import xml.etree.ElementTree as ET

    from rosbags.rosbag2 import Reader

    from .conftest import ROOT

    urdf = ROOT / "tests/data/robots/phantomx_description/urdf/phantomx.urdf"
    revolute = {j.get("name") for j in ET.parse(urdf).getroot().iter("joint") if j.get("type") == "revolute"}
    for args in (["import", "urdf", str(urdf), "--out", str(tmp_path / "px")],
                 ["plan", str(tmp_path / "px/robots/PhantomX.toml"), "--duration", "1", "--out", str(tmp_path / "run"),
                  "--no-plots"],
                 ["export", "bag", str(tmp_path / "run"), "--out", str(tmp_path / "bag")]):
        code, _, stderr = run(args, capsys, monkeypatch)
        assert code == 0, stderr
    store = typestore_for("mcap")
    found: dict[str, object] = {}
    with Reader(tmp_path / "bag") as reader:
        for connection, _, data in reader.messages():
            if connection.topic not in found:
                found[connection.topic] = store.deserialize_cdr(data, connection.msgtype)
    names = list(found["/joint_states"].name)  # type: ignore[attr-defined]
    assert len(names) == 18 and set(names) == revolute
    assert list(found["/desired_joint_states"].name) == names  # type: ignore[attr-defined]
    description = found["/robot_description"].data  # type: ignore[attr-defined]
    assert all(f'<joint name="{name}"' in description for name in names)
    servo_map = json.loads(found["/shc/servo_map"].data)  # type: ignore[attr-defined]
    assert list(servo_map) == names
    assert servo_map["j_c1_rf"] == {"key": "AR_c1", "bus": 0, "id": 11, "model": "XM430-W350", "direction": 1,
                                    "zero_ticks": None}
    assert servo_map["j_tibia_lf"]["id"] == 63  # the left front leg is AL, the sixth: ids 61-63


def test_one_output_rule_for_export_bag(walked: Path, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """--overwrite replaces a bag (only a bag); each format has its own default name, so sqlite3 after the default
    mcap does not collide; a file-like --out of a ROS 2 bag (a folder) is refused in one line instead of making a
    folder runs/arc.mcap/ holding arc.mcap.mcap; a ROS 1 bag is a .bag file."""
    import shutil

    run_dir = tmp_path / "walk"
    shutil.copytree(walked, run_dir)
    assert run(["export", "bag", str(run_dir)], capsys, monkeypatch)[0] == 0
    assert run(["export", "bag", str(run_dir), "--format", "sqlite3"], capsys, monkeypatch)[0] == 0
    assert (tmp_path / "walk_bag" / "metadata.yaml").exists()
    assert (tmp_path / "walk_bag_sqlite3" / "metadata.yaml").exists()
    code, _, err = run(["export", "bag", str(run_dir)], capsys, monkeypatch)
    assert code == 2 and err == (f"error: {tmp_path / 'walk_bag'}: already exists (add --overwrite to replace it, or "
                                 "choose another --out)\n")
    stamp = (tmp_path / "walk_bag" / "metadata.yaml").stat().st_mtime_ns
    code, stdout, err = run(["export", "bag", str(run_dir), "--overwrite"], capsys, monkeypatch)
    assert code == 0 and stdout == f"wrote {tmp_path / 'walk_bag'}\n", err
    assert (tmp_path / "walk_bag" / "metadata.yaml").stat().st_mtime_ns != stamp
    assert sorted(p.name for p in (tmp_path / "walk_bag").iterdir()) == ["metadata.yaml", "walk_bag.mcap"]
    assert not list(tmp_path.glob(".*partial*"))
    (tmp_path / "notes").mkdir()
    code, _, err = run(["export", "bag", str(run_dir), "--out", str(tmp_path / "notes"), "--overwrite"], capsys,
                       monkeypatch)
    assert code == 2 and "is not a bag, so --overwrite does not replace it" in err
    for fmt, name in (("mcap", "arc.mcap"), ("sqlite3", "arc.db3")):
        code, _, err = run(["export", "bag", str(run_dir), "--format", fmt, "--out", str(tmp_path / name)], capsys,
                           monkeypatch)
        assert code == 2 and err.count("\n") == 1, err
        assert err.startswith(f"error: {tmp_path / name}: --out is the folder that will hold a ROS 2 bag")
        assert f"give a folder, e.g. --out {tmp_path / 'arc'}" in err
        assert not (tmp_path / name).exists()
    code, _, err = run(["export", "bag", str(run_dir), "--format", "ros1", "--out", str(tmp_path / "arc.mcap")],
                       capsys, monkeypatch)
    assert code == 2 and "--format ros1 writes one .bag file; give --out NAME.bag" in err


def test_import_refuses_a_file_like_out(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """`shc import urdf FILE --out X/robot.toml` made a folder named robot.toml (issue 37): one line instead."""
    from .conftest import GOLDEN, ROOT

    urdf = ROOT / "tests" / "data" / "robots" / "hexapod_olli_io.urdf"
    out = tmp_path / "X" / "robot.toml"
    code, _, err = run(["import", "urdf", str(urdf), "--out", str(out)], capsys, monkeypatch)
    assert code == 2 and err.startswith(f"error: {out}: --out is the folder that will hold robots/NAME.toml"), err
    assert f"give a folder, e.g. --out {tmp_path / 'X'}" in err and not (tmp_path / "X").exists()
    code, _, err = run(["import", "openshc", str(GOLDEN / "openshc" / "bullet_insectoid.yaml"), "--out", str(out)],
                       capsys, monkeypatch)
    assert code == 2 and "--out is the folder that will hold robots/, gaits/ and poses/" in err
    assert not (tmp_path / "X").exists()


def test_import_urdf_refuses_an_existing_robot_file_without_overwrite(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                      monkeypatch) -> None:
    """The one output rule (issue 42.6): a second import into the same folder replaced the robot file silently."""
    from .conftest import ROOT

    urdf = ROOT / "tests" / "data" / "robots" / "hexapod_olli_io.urdf"
    out = tmp_path / "imported"
    code, _, err = run(["import", "urdf", str(urdf), "--out", str(out)], capsys, monkeypatch)
    assert code == 0, err
    [robot_file] = (out / "robots").glob("*.toml")
    robot_file.write_text(robot_file.read_text() + "# edited by hand\n")
    code, _, err = run(["import", "urdf", str(urdf), "--out", str(out)], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and f"{robot_file}: already exists (add --overwrite" in err, err
    assert robot_file.read_text().endswith("# edited by hand\n")
    code, _, err = run(["import", "urdf", str(urdf), "--out", str(out), "--overwrite"], capsys, monkeypatch)
    assert code == 0, err
    assert not robot_file.read_text().endswith("# edited by hand\n")
