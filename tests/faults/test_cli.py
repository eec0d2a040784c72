"""Bad fault descriptions on the command line (issue 34, "Done when": "Bad fault descriptions
(unknown kind, probability outside 0..1, negative time, unknown command) give one line and exit
2"; docs/cli.md: a user error is one line on stderr and exit status 2)."""
from __future__ import annotations

import pytest

import opentmcl
from opentmcl.host.errors import TmclUrlError

from ..capture.helpers import cli
from .helpers import plan_file

BAD = {
    "unknown kind": ([{"kind": "melt", "at": 1}], "unknown fault kind 'melt'"),
    "probability above 1": ([{"kind": "drop_reply", "probability": 1.5}], "probability: must be 0..1"),
    "probability below 0": ([{"kind": "drop_reply", "probability": -0.5}], "probability: must be 0..1"),
    "negative time": ([{"kind": "drop_reply", "at": -2}], "at: must be >= 0"),
    "negative duration": ([{"kind": "hang", "at": 1, "duration": -1}], "duration: must be >= 0"),
    "unknown command": ([{"kind": "drop_reply", "command": "JUMP", "count": 1}], "unknown TMCL mnemonic 'JUMP'"),
    "no module there": ([{"kind": "hang", "at": 1, "duration": 1, "address": 9}], "no module at address 9"),
}


def one_line_exit_2(out, needle: str) -> None:
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("\n") == 1 and needle in out.stderr, out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize("case", sorted(BAD))
def test_serve_refuses_a_bad_fault_file(tmp_path, case):
    faults, needle = BAD[case]
    one_line_exit_2(cli("serve", "-m", "TMCM-6212", "--tcp", "127.0.0.1:0", "--faults",
                        str(plan_file(tmp_path, faults))), needle)


def test_serve_refuses_a_file_that_is_no_plan(tmp_path):
    broken = tmp_path / "broken.toml"
    broken.write_text("[[fault]\n", encoding="utf-8")
    one_line_exit_2(cli("serve", "-m", "TMCM-6212", "--faults", str(broken)), "broken.toml")
    one_line_exit_2(cli("serve", "-m", "TMCM-6212", "--faults", str(tmp_path / "missing.toml")), "missing.toml")
    one_line_exit_2(cli("serve", "-m", "TMCM-6212", "--fault-seed", "3"), "belong to --faults FILE")


def test_a_bad_plan_in_a_sim_url(tmp_path):
    path = plan_file(tmp_path, [{"kind": "drop_reply", "probability": 2}])
    one_line_exit_2(cli("send", "--to", f"sim://TMCM-6212?faults={path}", "GAP 4, 0"), "must be 0..1")
    one_line_exit_2(cli("send", "--to", f"sim://TMCM-6212?faults={plan_file(tmp_path, [])}&seed=-1", "GAP 4, 0"),
                    "seed: must be 0..")


@pytest.mark.parametrize(("query", "needle"), [
    ("faults=", "faults= needs a fault file"),
    ("seed=3", "seed= belongs to faults=FILE"),
    ("faults={hang9}", "no module at address 9"),
])
def test_a_sim_url_refuses_what_serve_refuses(tmp_path, query, needle):
    """A blank faults=, a seed without faults (`serve --fault-seed` without --faults is refused
    too) and a module fault for an address no module has (as `serve` says "no module at address"):
    a TmclUrlError of one line (on the command line: one line, exit 2, as above)."""
    hang9 = plan_file(tmp_path, [{"kind": "hang", "at": 1, "duration": 1, "address": 9}])
    with pytest.raises(TmclUrlError) as info:
        opentmcl.connect(f"sim://TMCM-6212?{query.format(hang9=hang9)}")
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_the_control_socket_does_not_replace_a_file(tmp_path):
    taken = tmp_path / "taken"
    taken.write_text("mine", encoding="utf-8")
    one_line_exit_2(cli("serve", "-m", "TMCM-6212", "--tcp", "127.0.0.1:0", "--faults",
                        str(plan_file(tmp_path, [{"name": "x", "kind": "drop_reply"}])), "--fault-control",
                        str(taken)), "is not a socket")
    assert taken.read_text(encoding="utf-8") == "mine"
