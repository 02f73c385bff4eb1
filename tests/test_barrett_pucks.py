"""The BH8-280 commanded like the real one: puck firmware and libbarrett's Hand calls on a simulated hand.

Truths used: the gear ratios and encoder resolution (4096 counts/rev; 125, 93.75, 17.5 : 1), the puck defaults
(MT 2200 / IPNM 103125 = 0.0213 N m, MV, ACCEL, CT), the closed-form trapezoid, the response of a first-order loop
(the simulated motor is a damper b_m; the stated PID scale gives kp, kd), and static equilibrium under a
disturbance.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett import FINGER_PUCK, SPREAD_PUCK, BarrettDriver, BarrettTransmission, Puck, PuckProperties
from bhgrasp.barrett.readout import S_FINGERTIP_TORQUE, S_POSITION, S_TACT_FULL
from bhgrasp.barrett.transmission import MAX_MOTOR_TORQUE, MOTOR_DAMPING
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.mount import mounted
from bhgrasp.model.objects import Box
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

CPR = 4096 / (2 * np.pi)  # encoder counts per motor radian
MT = MAX_MOTOR_TORQUE  # [N m] puck torque limit at the motor (MT 2200 / IPNM)
IPNM = 2200 / MAX_MOTOR_TORQUE  # 103125 puck units per N m
F1P, F1D, F2P, F2D, F3P, F3D = 1, 2, 4, 5, 6, 7  # joint indices of the packaged hand
SCALE = 1024  # the PID scale bhgrasp.barrett.pucks documents (KP counts -> puck units / 1024)


def _sim(hand: bh.Hand, objects=(), self_locking: bool = True) -> Simulator:
    contact = SpringDamper(5e4, 50.0)
    actuation = BarrettActuation(hand, self_locking=self_locking)
    return Simulator(Scene(hand, objects), dt=1e-3, actuation=actuation, contact=contact)


def _gains(kp_units: float, kd_units: float) -> tuple[float, float]:
    """kp [N m/rad], kd [N m s/rad] at the motor from KP, KD: units / 1024 per count (per count/ms), / IPNM."""
    return kp_units * CPR / (SCALE * IPNM), kd_units * CPR * 1e-3 / (SCALE * IPNM)


def test_encoders_and_link_angles_follow_the_gear_ratios() -> None:
    """update() reads both encoders; libbarrett's link formulas read the secondary encoder (exact after breakaway)
    unless enableBreakawayEncoders(false), whose P-only formula is right only before breakaway."""
    hand = bh.BarrettHand()
    driver = BarrettDriver(hand)
    q = hand.configuration(
        F1_spread=1.2,
        F2_spread=1.2,
        F1_proximal=0.8,
        F1_distal=0.8 / 3,
        F2_proximal=0.5,
        F2_distal=0.6,
        F3_proximal=2.0,
        F3_distal=2.0 / 3,
    )
    driver.reset(State(t=0.0, q=q, v=np.zeros(8)))
    with pytest.raises(InputError, match=r"no reading yet: call update\(\)"):
        driver.primary_encoder_positions()
    driver.update()
    counts = driver.primary_encoder_positions()
    # armed: motor = 125 q_proximal; broken away (F2): motor = 93.75 (q_proximal + q_distal); spread 17.5 q
    expected = [125 * 0.8 * CPR, 93.75 * 1.1 * CPR, 125 * 2.0 * CPR, 17.5 * 1.2 * CPR]
    np.testing.assert_array_equal(counts, np.rint(expected))
    assert counts[0] == 65190  # 0.8 rad x 125 x 4096 / 2 pi = 65189.86
    np.testing.assert_array_equal(driver.secondary_encoder_positions(), np.rint(50 * CPR * np.array([0.8, 0.5, 2.0])))
    resolution = 0.5 / (50 * CPR) + 0.5 / (93.75 * CPR)  # [rad] half a count of each encoder
    np.testing.assert_allclose(driver.inner_link_positions(), [0.8, 0.5, 2.0, 1.2], atol=resolution)
    np.testing.assert_allclose(driver.outer_link_positions()[:3], [0.8 / 3, 0.6, 2.0 / 3], atol=resolution)
    driver.enable_breakaway_encoders(False)  # P alone, from the next update: F2's breakaway travel reads as proximal
    assert driver.inner_link_positions()[1] == pytest.approx(0.5, abs=resolution)  # not yet
    driver.update()
    np.testing.assert_allclose(driver.inner_link_positions()[[0, 2]], [0.8, 2.0], atol=resolution)
    assert driver.inner_link_positions()[1] == pytest.approx(1.1 * 93.75 / 125, abs=resolution)  # not 0.5


def test_update_reads_the_options_the_hand_has() -> None:
    """has*() report the options; update(flags) reads the named sensors only; an absent option's getter says so."""
    hand = bh.BarrettHand()
    state = State(t=0.0, q=hand.neutral(), v=np.zeros(8))
    bare = BarrettDriver(hand, fingertip_torque_sensors=False, tactile_sensors=False)
    assert not bare.has_fingertip_torque_sensors() and not bare.has_tact_sensors()
    with pytest.raises(InputError, match="sensed no state yet"):
        bare.update()
    bare.reset(state)
    bare.update()
    with pytest.raises(InputError, match="this hand has no fingertip torque sensors"):
        bare.fingertip_torque()
    with pytest.raises(InputError, match="this hand has no tactile pads"):
        bare.tactile()
    full = BarrettDriver(hand)
    assert full.has_fingertip_torque_sensors() and full.has_tact_sensors()
    full.reset(state)
    full.update(S_POSITION | S_FINGERTIP_TORQUE)
    assert full.fingertip_torque().tolist() == [2064, 2064, 2064]  # unloaded: "around 2000"
    with pytest.raises(InputError, match="no reading yet"):
        full.tactile()
    full.update(S_TACT_FULL)
    assert full.tactile().shape == (4, 24) and not full.tactile().any()
    for bad in (8, -1, True, 1.0, "S_ALL"):
        with pytest.raises(InputError, match="`sensors` must be an OR of S_POSITION 1"):
            full.update(bad)


def test_initialize_homes_the_fingers_then_the_spread_and_zeroes_the_encoders() -> None:
    """A hand powered on half closed counts 0 where it stands; initialize() opens the fingers to their stops, then
    the spread, and zeroes there: afterwards the counts are the gear train's from the open stops (to the joint
    stops' give), and a trapezoidal move lands where libbarrett's units say."""
    hand = bh.BarrettHand()
    q0 = hand.configuration(
        F1_spread=0.6,
        F2_spread=0.6,
        F1_proximal=0.8,
        F1_distal=0.8 / 3,
        F2_proximal=1.2,
        F2_distal=0.4,
        F3_proximal=0.5,
        F3_distal=0.5 / 3,
    )
    simulator = _sim(hand)
    driver = BarrettDriver(hand, homed=False)
    driver.reset(simulator.initial_state(q0))
    driver.update()
    assert not driver.primary_encoder_positions().any() and not driver.secondary_encoder_positions().any()
    driver.script([(0.0, "initialize"), ("done", "trapezoidal_move", [1.0, 1.0, 1.0, 0.5])])
    trajectory = simulator.run(driver, 3.0, state=simulator.initial_state(q0), progress=False)
    modes = trajectory.log["puck_modes"]
    fingers_done = int(np.argmax((modes[:, :3] == 0).all(axis=1)))  # HOLD 0: IDLE once homed
    spread_moves = int(np.argmax(np.abs(trajectory.q[:, 0] - 0.6) > 1e-3))
    assert 0 < fingers_done <= spread_moves  # the spread waits for the fingers (Hand::initialize)
    assert np.abs(trajectory.q[fingers_done, [F1P, F2P, F3P]]).max() < 5e-3  # the fingers at their open stops
    assert driver.done_moving()
    driver.update()
    q = trajectory.q[-1]
    truth = np.array([q[F1P], q[F2P], q[F3P], q[0]])
    give = 5e-3  # [rad] how far the joint stops let the links past 0 when each puck zeroed
    np.testing.assert_allclose(driver.inner_link_positions(), truth, atol=give)
    np.testing.assert_allclose(truth, [1.0, 1.0, 1.0, 0.5], atol=give)  # the move's targets, in absolute angles


def test_motor_torque_never_exceeds_mt() -> None:
    """Torque mode passes jt / ratio (libbarrett's j2pt) and clips at MT = 0.0213 N m, as does a far PID set point."""
    hand = bh.BarrettHand()
    driver = BarrettDriver(hand)
    state = State(t=0.0, q=hand.configuration(F1_proximal=0.5, F1_distal=0.5 / 3), v=np.zeros(8))
    driver.reset(state)
    driver.set_torque_mode()
    driver.set_torque([0.5, -30.0, 30.0, 0.3])  # joint torques [N m]: F1, F2, F3, SPREAD
    u = driver(0.0, state)  # SPREAD, F1, F2, F3 motor torques
    np.testing.assert_allclose(u, [0.3 / 17.5, 0.5 / 125, -MT, MT], rtol=1e-12)
    driver.set_position_mode("F1")
    driver.set_position([2.4, 0, 0, 0], "F1")  # 1.9 rad away: the PID saturates
    assert driver(1e-3, state)[1] == pytest.approx(MT, rel=1e-12)
    trajectory = _sim(hand).run(BarrettDriver(hand, finger=FINGER_PUCK.with_(HOLD=1)), 0.3, progress=False)
    assert np.abs(trajectory.log["motor_torques"]).max() <= MT + 1e-15  # the same from a simulated run
    driver.idle()
    assert not driver(2e-3, state).any()


def _trapezoid_speed(t_ms: np.ndarray, distance: float, v_max: float, accel: float) -> np.ndarray:
    """Closed-form rest-to-rest trapezoid: speed [counts/ms] at ``t_ms``; distance [counts], accel [counts/ms^2]."""
    ramp = v_max / accel
    total = distance / v_max + ramp
    t = np.minimum(t_ms, total)
    return np.minimum.reduce([accel * t, np.full_like(t, v_max), accel * (total - t)])


def test_trapezoidal_move_follows_the_closed_form_profile() -> None:
    """F1 to 1 rad at MV = 100 counts/ms, ACCEL 200 (x 1/256 counts/ms^2): plateau at MV, ends at the target."""
    hand = bh.BarrettHand(gravity=(0.0, 0.0, 0.0))
    props = FINGER_PUCK.with_(MV=100.0)
    driver = BarrettDriver(hand, finger=props)
    driver.script([(0.0, "trapezoidal_move", [1.0, 0.0, 0.0, 0.0], "F1")])
    trajectory = _sim(hand).run(driver, 1.2, progress=False)
    speed = (trajectory.v[:, F1P] + trajectory.v[:, F1D]) * 93.75 * CPR * 1e-3  # motor [counts/ms]
    t_ms = trajectory.t * 1e3
    distance, accel = 1.0 * 125 * CPR, 200 / 256
    ideal = _trapezoid_speed(t_ms, distance, 100.0, accel)
    ramp, total = 100.0 / accel, distance / 100.0 + 100.0 / accel  # 128 ms, 943 ms
    plateau = (t_ms > ramp + 200) & (t_ms < total - ramp)
    np.testing.assert_allclose(speed[plateau], 100.0, rtol=2e-3)  # peak = MV
    assert speed.max() < 100.5
    # The loop on the simulated motor (a damper b_m): (b_m + kd) e' = b_m r' - kp e, speed = r' - e' (e = r - x)
    kp, kd = _gains(500, 2500)
    e, response, h = 0.0, [], 1e-5
    for t in np.arange(0.0, total * 1e-3, h):
        rate = _trapezoid_speed(np.array([t * 1e3]), distance, 100.0, accel)[0] * 1e3 / CPR  # [rad/s]
        de = (MOTOR_DAMPING * rate - kp * e) / (MOTOR_DAMPING + kd)
        response.append((rate - de) * CPR * 1e-3)
        e += h * de
    moving = t_ms < total - 5
    model = np.interp(t_ms[moving], np.arange(len(response)) * h * 1e3, response)
    assert np.abs(speed[moving] - model).max() < 1.0  # ramps at ACCEL through the loop's lag: within 1 % of MV
    assert np.abs(speed[moving] - ideal[moving]).max() > 10  # (the lag is real: the raw trapezoid is not matched)
    assert trajectory.q[-1, F1P] == pytest.approx(1.0, abs=100 / (125 * CPR))  # within 100 counts of E
    assert driver.done_moving("F1") and driver.modes()["F1"] == "IDLE"  # HOLD = 0: idle once there


def test_velocity_mode_reaches_the_commanded_speed() -> None:
    hand = bh.BarrettHand()
    driver = BarrettDriver(hand)
    driver.script([(0.0, "velocity_move", {"F2": 1.0, "SPREAD": 0.5}, ["F2", "SPREAD"])])
    trajectory = _sim(hand).run(driver, 1.2, progress=False)
    late = trajectory.t > 0.9  # the spread, carrying F1 and F2 on its weak motor, settles last
    np.testing.assert_allclose(trajectory.v[late, F2P], 1.0, rtol=5e-3)  # inner link [rad/s]
    np.testing.assert_allclose(trajectory.v[late, 0], 0.5, rtol=5e-3)  # spread [rad/s]
    assert not trajectory.log["puck_modes"][:, 0].any() and not driver.done_moving("F2")  # F1 idle, F2 running


def test_close_in_free_air_ends_at_the_close_target_and_open_returns() -> None:
    """close(): fingers to CT = 195000 counts (2.393 rad), the spread to its pi stop (CT 35950 lies past it)."""
    hand = bh.BarrettHand()
    driver = BarrettDriver(hand, finger=FINGER_PUCK.with_(HOLD=1))
    driver.script([(0.0, "close"), ("done", "open", "GRASP")])
    trajectory = _sim(hand).run(driver, 2.6, progress=False)
    modes = trajectory.log["puck_modes"]
    closed = int(np.argmax((modes[:, :3] == 3).all(axis=1)))  # the fingers' pucks hold (HOLD = 1): done
    assert 0.8 < trajectory.t[closed] < 1.5
    np.testing.assert_allclose(trajectory.q[closed, [F1P, F2P, F3P]], 195000 / (125 * CPR), atol=100 / (125 * CPR))
    assert trajectory.q[closed, 0] == pytest.approx(np.pi, abs=1e-3)  # spread at its stop
    assert modes[closed, 3] == 3  # the spread stalled there for TSTOP and holds (its HOLD = 1)
    assert np.abs(trajectory.q[-1, [F1P, F2P, F3P]]).max() < 100 / (125 * CPR)  # open: back to OT = 0
    assert driver.done_moving()


def test_close_on_an_object_stalls_on_contact_and_reports_done() -> None:
    hand = bh.BarrettHand()
    """F3 closes on a stiffly sprung box (as in test_actuation): its proximal link stops there, breaks away, the tip
    curls to its stop, and the puck stops after TSTOP = 50 ms without motion (HOLD = 0: IDLE)."""
    box = SpringMounted(
        Box(size=(0.04, 0.02, 0.02), mass=0.5, pose=pin.SE3(np.eye(3), np.array([0.0, 0.095, 0.115]))),
        direction=(0, 0, 1),
        stiffness=1e5,
        damping=50.0,
    )
    driver = BarrettDriver(hand)
    driver.script([(0.0, "close", "F3")])
    trajectory = _sim(hand, [box]).run(driver, 2.0, progress=False)
    idle = trajectory.log["puck_modes"][:, 2] == 0  # F3's puck, HOLD = 0
    k = int(np.argmax(idle[1:])) + 1
    assert idle[k:].all() and driver.done_moving("F3")
    assert trajectory.contact_count()[k] > 0  # it stopped touching the box
    assert trajectory.q[k, F3P] < 195000 / (125 * CPR) - 0.5  # far short of the close target
    window = slice(k - 45, k)  # the samples of the TSTOP = 50 ms (less a few for the sensing delay)
    speed = (trajectory.v[window, F3P] + trajectory.v[window, F3D]) * 93.75 * CPR * 1e-3
    assert np.abs(speed).max() < 1.0  # stalled (< 1 count/ms) for the TSTOP = 50 ms before
    assert trajectory.modes[k, 2] == 1  # F3's TorqueSwitch broke away on the box
    assert not (trajectory.log["puck_modes"][:, [0, 1, 3]]).any()  # the other pucks stayed IDLE


def test_pid_hold_gives_way_by_the_disturbance_over_its_stiffness() -> None:
    """Through back-drivable gears of efficiency eta, a proximal disturbance d moves a held finger by
    d / (eta 125^2 kp) (kp from KP 500) and the motor pushes -d / (eta 125); the real self-locking worm gives 0."""
    hand = bh.BarrettHand()
    for self_locking in (False, True):
        sim = _sim(hand, self_locking=self_locking)
        start = sim.initial_state(hand.configuration(F2_proximal=0.8, F2_distal=0.8 / 3))
        driver = BarrettDriver(hand)
        driver.script([(0.0, "set_position_mode", "F2")])
        disturbance = np.zeros(8)
        disturbance[F2P] = 0.3  # [N m] closing, below the 0.5 N m breakaway
        push = disturbance.copy()
        trajectory = sim.run(
            driver, 0.8, state=start, progress=False, disturbance=lambda t, push=push: push if t >= 0.4 else np.zeros(8)
        )
        kp, _ = _gains(500, 2500)
        eta = sim.actuation.drive.efficiency
        k = np.flatnonzero(trajectory.t < 0.4)[-1]  # steady before the disturbance (it holds against gravity)
        moved = trajectory.q[-1, F2P] - trajectory.q[k, F2P]
        assert not trajectory.modes[:, :3].any()
        if self_locking:
            assert moved == 0.0  # the worm does not let the load turn it
            continue
        assert moved == pytest.approx(0.3 / (eta * 125**2 * kp), rel=0.05)  # 2.4 mrad
        torques = trajectory.log["motor_torques"][:, 1]
        assert torques[-1] - torques[k] == pytest.approx(-0.3 / (eta * 125), rel=0.02)


def test_the_back_drivable_spread_gives_way_by_the_load_over_its_stiffness_and_to_its_stop_past_mt() -> None:
    """The spread's puck holds its position (HOLD = 1) through spur gears without a worm: a load d on the spread
    moves it by d / (17.5^2 kp) (kp from the spread's KP 1000) and it returns; past 17.5 MT = 0.37 N m the puck
    saturates and the load pushes the spread to its stop."""
    hand = bh.BarrettHand()
    kp = 1000 * CPR / (SCALE * IPNM)  # [N m/rad] at the motor
    for load, expected in ((0.1, 0.1 / (17.5**2 * kp)), (0.5, np.pi - 1.0)):
        sim = _sim(hand)
        start = sim.initial_state(hand.configuration(F1_spread=1.0, F2_spread=1.0))
        driver = BarrettDriver(hand)
        driver.script([(0.0, "set_position_mode", "SPREAD")])
        push = np.zeros(8)
        push[0] = load
        disturbance = lambda t, push=push: push if 0.5 <= t < 2.0 else np.zeros(8)  # noqa: E731
        trajectory = sim.run(driver, 3.0, state=start, progress=False, disturbance=disturbance)
        held, pushed = (int(np.searchsorted(trajectory.t, t)) for t in (0.45, 1.99))
        moved = trajectory.q[pushed, 0] - trajectory.q[held, 0]
        assert moved == pytest.approx(expected, rel=0.02)  # 0.053 rad, or to the pi stop
        assert abs(trajectory.q[-1, 0] - trajectory.q[held, 0]) < 1e-3  # it returns when the load goes
    assert 17.5 * MT == pytest.approx(0.3733, abs=1e-4)


def test_a_mounted_hand_gets_zero_on_its_mount_and_the_pucks_tick_at_1_khz() -> None:
    hand = mounted(bh.BarrettHand())
    driver = BarrettDriver(hand)
    state = State(t=0.0, q=np.zeros(hand.nq), v=np.zeros(hand.nv))
    driver.reset(state)
    driver.set_torque_mode()
    driver.set_torque([1.25, 0.0, 0.0, 0.0])
    u = driver(0.0, state)
    assert u.shape == (BarrettTransmission(hand).n_inputs,) and not u[4:].any() and u[1] == pytest.approx(0.01)
    driver.set_torque([2.5, 0.0, 0.0, 0.0])
    assert driver(0.0005, state)[1] == pytest.approx(0.01)  # held until the next 1 ms tick
    assert driver(0.001, state)[1] == pytest.approx(0.02)


@pytest.mark.filterwarnings("ignore:URDF")  # the Allegro URDF's inertias (a known warning of its asset)
def test_bad_inputs_raise_input_errors_naming_the_value(allegro: bh.Hand) -> None:
    hand = bh.BarrettHand()
    driver = BarrettDriver(hand)
    with pytest.raises(bh.InputError, match="unknown digit 'F4'; valid digits: F1, F2, F3, SPREAD, GRASP"):
        driver.close("F4")
    with pytest.raises(bh.InputError, match=r"`positions` must have shape \(4,\), got shape \(3,\)"):
        driver.trapezoidal_move([1.0, 1.0, 1.0])
    with pytest.raises(bh.InputError, match="`velocities` must be finite"):
        driver.velocity_move([np.nan, 0, 0, 0])
    with pytest.raises(bh.InputError, match="unknown command 'squeeze'"):
        driver.script([(0.0, "squeeze")])
    with pytest.raises(bh.InputError, match="a script step must be .* got \\('soon', 'close'\\)"):
        driver.script([("soon", "close")])
    with pytest.raises(bh.InputError, match="HOLD must be 0 or 1, got 2"):
        FINGER_PUCK.with_(HOLD=2)
    with pytest.raises(bh.InputError, match="MT must be a finite non-negative number .* got -1"):
        PuckProperties(MT=-1)
    with pytest.raises(bh.InputError, match=r"unknown puck properties \['KQ'\]"):
        SPREAD_PUCK.with_(KQ=3)
    with pytest.raises(bh.InputError, match="puck MODE must be one of .* got 7"):
        Puck(FINGER_PUCK, (0.0, 1e5)).set_mode(7, 0.0)
    with pytest.raises(bh.InputError, match="kp > 0"):
        BarrettDriver(hand, finger_gains=(0.0, 0.0, 0.0))
    with pytest.raises(bh.InputError, match="lacks joints"):
        BarrettDriver(allegro)
    with pytest.raises(bh.InputError, match=r"`finger` must be PuckProperties or three of them"):
        BarrettDriver(hand, finger=(FINGER_PUCK, FINGER_PUCK))
    with pytest.raises(bh.InputError, match="unknown puck property 'IPNM'"):
        driver.set_property("IPNM", 1.0)
    with pytest.raises(bh.InputError, match="MT must be a finite non-negative number .* got -5"):
        driver.set_property("MT", -5.0, "F1")


def test_each_puck_takes_its_own_properties_at_build_and_by_set_property() -> None:
    """Per-finger MT (libbarrett sets properties puck by puck): a far PID set point saturates each finger's motor at
    its own MT / IPNM, and set_property changes it at the next tick for the named digits only."""
    hand = bh.BarrettHand()
    state = State(t=0.0, q=hand.configuration(F1_proximal=0.5, F1_distal=0.5 / 3), v=np.zeros(8))
    driver = BarrettDriver(hand, finger=(FINGER_PUCK.with_(MT=1100), FINGER_PUCK.with_(MT=550), FINGER_PUCK))
    driver.reset(state)
    driver.set_position_mode("GRASP")
    driver.set_position([2.4, 2.4, 2.4, 0.0], "GRASP")  # far: every finger's PID saturates
    np.testing.assert_allclose(driver(0.0, state)[1:4], [1100 / IPNM, 550 / IPNM, MT], rtol=1e-12)
    driver.set_property("MT", 220, ["F2", "F3"])
    np.testing.assert_allclose(driver(1e-3, state)[1:4], [1100 / IPNM, 220 / IPNM, 220 / IPNM], rtol=1e-12)
