"""`opentmcl.pytest_plugin.make_tmcl_module` and `TmclModule.advance` raise the host library's typed
errors (issue 11: "every argument error raises a TmclError subclass with a one-line message (keep
ValueError/IndexError as a second base)"; "timeouts must be finite and positive"). The address
rule is the one of `opentmcl serve`: 1..255, global parameter 66 (TMCM-6212 manual 5.1)."""
from __future__ import annotations

import math

import pytest

from opentmcl.host.errors import TmclTypeError, TmclValueError
from opentmcl.pytest_plugin import make_tmcl_module


@pytest.mark.parametrize("address", [1, 255])
def test_first_and_last_address(address):
    module = make_tmcl_module(address=address)
    try:
        assert module.get_global(66) == address          # GGP 66: the serial address
    finally:
        module.close()


@pytest.mark.parametrize("address", [0, 256, -1])
def test_addresses_outside_1_to_255_are_typed_value_errors(address):
    with pytest.raises(TmclValueError, match=r"1\.\.255") as info:
        make_tmcl_module(address=address)
    assert isinstance(info.value, ValueError) and "\n" not in str(info.value)


@pytest.mark.parametrize("address", ["1", 1.0, True, None])
def test_an_address_of_the_wrong_type_is_a_typed_type_error(address):
    with pytest.raises(TmclTypeError) as info:
        make_tmcl_module(address=address)
    assert isinstance(info.value, TypeError)


@pytest.mark.parametrize("timeout", [0, -1, math.nan, math.inf, -math.inf])
def test_timeouts_must_be_finite_and_positive(timeout):
    with pytest.raises(TmclValueError, match="positive, finite"):
        make_tmcl_module(timeout=timeout)


def test_smallest_timeout_is_accepted_and_a_string_is_a_type_error():
    make_tmcl_module(timeout=5e-324).close()   # the smallest positive float
    with pytest.raises(TmclTypeError):
        make_tmcl_module(timeout="5")


@pytest.mark.parametrize("seconds", [-1e-9, math.nan, math.inf])
def test_advance_refuses_negative_and_non_finite_time(seconds):
    """advance(inf) used to reach the virtual module's own plain ValueError; NaN too."""
    module = make_tmcl_module()
    try:
        with pytest.raises(TmclValueError, match="finite"):
            module.advance(seconds)
        module.advance(0)                              # the last valid value: nothing happens
        assert module.time == 0
    finally:
        module.close()
