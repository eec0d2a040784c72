"""Reference search edges left unpinned by the seeded firmware mutation sample (issue 12, group b)."""
from opentmcl import VirtualModule

from .test_reference import STAGE


def test_a_search_without_a_search_speed_parameter_stands_until_rfs_stop(tmp_path):
    """TMCM-6212 3.6.11 RFS (START 0, STOP 1, STATUS 2) and 4.1 AP194 "Reference search speed";
    docs/profiles.md `[remove]`. On a profile without AP194 the speed of the switch search reads
    as 0 (as a parameter the module lacks reads through `get_raw`): the motor does not leave 0,
    the search stays active (STATUS 1), and RFS STOP ends it (STATUS 0)."""
    path = tmp_path / "nospeed.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOSPEED-6212"\n'
                    "[remove]\naxis_parameter = [194]\n")
    vm = VirtualModule(str(path), scenario=STAGE)
    assert vm.request(6, 194, 0).status == 3
    assert vm.request(13, 0, 0).status == 100
    vm.advance(1.0)
    assert (vm.request(13, 2, 0).value, vm.request(6, 1, 0).value) == (1, 0)
    assert vm.request(13, 1, 0).status == 100
    assert vm.request(13, 2, 0).value == 0
