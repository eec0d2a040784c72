"""The Step/Dir output stage as a stream of timed edges (datasheet 6.2.1, 8.1)."""
from opentmcl.chips.tmc4210.stepdir import StepDirOutput


def make(**conf):
    out = StepDirOutput(16_000_000)
    out.capture = True
    cfg = dict(en_sd=1, step_half=0, inv_stp=0, inv_dir=0, t_step=16 * 4)
    cfg.update(conf)
    out.configure(0, **cfg)
    out.drain()
    return out


def test_outputs_high_and_silent_until_en_sd():
    """6.2.1: "After power-on, the output signals are logic high until they become configured";
    1.4: the interface has to be initialized by writing 1 to en_sd."""
    out = StepDirOutput(16e6)
    out.capture = True
    out.step(100, 1)
    assert (out.step_level, out.dir_level) == (1, 1)
    assert out.drain() == []
    out.configure(200, en_sd=1, step_half=0, inv_stp=0, inv_dir=0, t_step=256)
    assert [(e.cycle, e.pin, e.level) for e in out.drain()] == [(200, "STEP", 0)]


def test_pulse_length_is_t_step():
    """8.1: step pulse length t_STEP = 16 * (1 + STPDIV_4210) clock cycles."""
    out = make(t_step=16 * (1 + 3))
    out.step(1000, 1)
    edges = out.drain()
    assert [(e.cycle, e.pin, e.level) for e in edges] == [(1000, "STEP", 1), (1064, "STEP", 0)]
    assert edges[1].time == 1064 / 16e6


def test_first_step_after_direction_change_is_delayed_by_t_step():
    """8.1: "The first step pulse after a change of direction is delayed by t_DIR2STP which is equal to t_STEP"."""
    out = make(t_step=32)
    out.step(1000, 1)
    out.step(2000, -1)
    out.step(3000, -1)
    got = [(e.cycle, e.pin, e.level) for e in out.drain()]
    assert got == [(1000, "STEP", 1), (1032, "STEP", 0), (2000, "DIR", 0), (2032, "STEP", 1),
                   (2064, "STEP", 0), (3000, "STEP", 1), (3032, "STEP", 0)]


def test_inv_stp_and_inv_dir_invert_the_levels():
    """6.2.1: inv_stp inverts the step pulse polarity, inv_dir the direction output."""
    out = make(inv_stp=1, inv_dir=1, t_step=16)
    assert (out.step_level, out.dir_level) == (1, 0)
    out.drain()
    out.step(100, 1)
    out.step(500, -1)
    got = [(e.cycle, e.pin, e.level) for e in out.drain()]
    assert got == [(100, "STEP", 0), (116, "STEP", 1), (500, "DIR", 1), (516, "STEP", 0), (532, "STEP", 1)]


def test_step_half_toggles_once_per_step():
    """6.2.1: step_half "toggle on each step pulse ... both pulse edges represent steps"."""
    out = make(step_half=1, t_step=256)
    out.drain()
    for c in (100, 200, 300):
        out.step(c, 1)
    assert [(e.cycle, e.level) for e in out.drain()] == [(100, 1), (200, 0), (300, 1)]


def test_steps_faster_than_the_pulse_length_are_merged():
    """8.1: STPDIV_4210 "has to be set compatible to the upper step frequency"; a step that
    comes while the pulse is still active is not seen by the driver."""
    out = make(t_step=256)
    out.step(0, 1)
    out.step(100, 1)
    out.step(300, 1)
    assert out.steps_out == 2 and out.lost_steps == 1


def test_drain_returns_edges_in_time_order_up_to_a_cycle():
    out = make(t_step=50)
    out.step(10, 1)
    assert [e.cycle for e in out.drain(30)] == [10]
    assert [e.cycle for e in out.drain()] == [60]
