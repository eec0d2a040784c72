"""`opentmcl tmc4210 ...`: tools around the TMC4210 chip model.

    opentmcl tmc4210 pmulpdiv -a A_MAX -r RAMP_DIV -p PULSE_DIV [-pr P_REDUCTION]
        the PMUL/PDIV search of datasheet 6.1.9.2 and the A_MAX limits of 6.1.7.1.1,
        printed as the datasheet's example program pmulpdiv.c prints them
    opentmcl tmc4210 convert [-v V | --hz R] [-a A_MAX | --hz-per-s dR] -p PULSE_DIV [-r RAMP_DIV]
        register values <-> step rate (Hz) and change of step rate (Hz/s), 6.1.12
    opentmcl tmc4210 trace SCRIPT [--f-clk HZ]
        run a datagram script (or a Python file with main(chip)) and print every
        datagram in and out, decoded
"""
from __future__ import annotations

import argparse
import math

from . import CliError, float_arg, int_arg


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("tmc4210", help="TMC4210 chip model: PMUL/PDIV calculator, converters, trace",
                              description="Tools around the register-exact TMC4210 model.")
    sub = p.add_subparsers(dest="tmc4210_command", metavar="SUBCOMMAND")
    p.set_defaults(func=lambda args: _help(p))

    pm = sub.add_parser("pmulpdiv", help="PMUL/PDIV for an A_MAX (datasheet 6.1.9.2)")
    pm.add_argument("-a", dest="a_max", type=int_arg, required=True, help="A_MAX 0..2047")
    pm.add_argument("-r", dest="ramp_div", type=int_arg, required=True, help="RAMP_DIV 0..13")
    pm.add_argument("-p", dest="pulse_div", type=int_arg, required=True, help="PULSE_DIV 0..13")
    pm.add_argument("-pr", "--p-reduction", dest="p_reduction", type=float_arg, default=0.0,
                    help="reduction of p, 0.00 .. 0.10 (default 0)")
    pm.set_defaults(func=cmd_pmulpdiv)

    cv = sub.add_parser("convert", help="register values <-> Hz and Hz/s (datasheet 6.1.12)")
    g = cv.add_mutually_exclusive_group()
    g.add_argument("-v", "--velocity", type=int_arg, help="velocity register value (-2047..2047)")
    g.add_argument("--hz", type=float_arg, help="step rate in Hz")
    h = cv.add_mutually_exclusive_group()
    h.add_argument("-a", "--a-max", type=int_arg, help="A_MAX register value (0..2047)")
    h.add_argument("--hz-per-s", type=float_arg, help="change of step rate in Hz/s")
    cv.add_argument("-p", "--pulse-div", type=int_arg, required=True)
    cv.add_argument("-r", "--ramp-div", type=int_arg, default=None)
    cv.add_argument("--f-clk", type=float_arg, default=16e6, help="clock frequency in Hz (default 16 MHz)")
    cv.set_defaults(func=cmd_convert)

    tr = sub.add_parser("trace", help="run a datagram script and print every datagram, decoded")
    tr.add_argument("script", help="text script (see docs/tmc4210.md) or Python file with main(chip)")
    tr.add_argument("--f-clk", type=float_arg, default=16e6, help="clock frequency in Hz (default 16 MHz)")
    tr.set_defaults(func=cmd_trace)


def _help(parser: argparse.ArgumentParser) -> int:
    parser.print_help()
    return 0


def _range(name: str, value: int, lo: int, hi: int) -> None:
    if not lo <= value <= hi:
        raise CliError(f"{name} must be {lo}..{hi}, got {value}")


def cmd_pmulpdiv(args: argparse.Namespace) -> int:
    _range("A_MAX (-a)", args.a_max, 0, 2047)
    _range("RAMP_DIV (-r)", args.ramp_div, 0, 13)
    _range("PULSE_DIV (-p)", args.pulse_div, 0, 13)
    if not math.isfinite(args.p_reduction) or not 0.0 <= args.p_reduction < 1.0:
        raise CliError(f"p_reduction (-pr) must be 0 <= pr < 1, got {args.p_reduction}")
    from ..motion.pmulpdiv import PmulPdivError

    try:
        print(format_pmulpdiv(args.a_max, args.ramp_div, args.pulse_div, args.p_reduction), end="")
    except PmulPdivError as exc:
        raise CliError(str(exc)) from None
    return 0


def format_pmulpdiv(a_max: int, ramp_div: int, pulse_div: int, p_reduction: float) -> str:
    """The report of the datasheet's example program (6.1.9.2.3), same quantities and layout."""
    from ..motion.pmulpdiv import calc_pmul_pdiv

    r = calc_pmul_pdiv(a_max, ramp_div, pulse_div, p_reduction)
    # the program reports "no valid pair" as -1 / -1 and still divides: p_best = -1 / 2^(-1+3)
    pmul, pdiv = (r.pmul, r.pdiv) if r.valid else (-1, -1)
    p_best = r.p_best if r.valid else -0.25
    e = ramp_div - pulse_div
    lower = int(2.0 ** (e - 1))  # the program's (int)pow(2, ramp_div-pulse_div-1)
    upper = int(2.0 ** (12 + e)) - 1
    out = [f"\n\n  a_max={a_max}\tramp_div={ramp_div}\tpulse_div={pulse_div}\tp_reduction={p_reduction:f}\n\n",
           f"    p_mul = {pmul:3d}\n    p_div = {pdiv:3d}\n\n",
           f"    p_ideal = {r.p_ideal:f}\n    p_best = {p_best:f}\n    p_redu = {r.p_reduced:f}\n\n",
           f"\n  a_max_lower_limit = {lower}"]
    if a_max < lower:
        out.append("    [WARNING: a_max < a_max_lower_limit]")
    out.append(f"\n  a_max_upper_limit = {upper}")
    if a_max > upper:
        out.append("    [WARNING: a_max > a_max_upper_limit]")
    out.append("\n\n")
    return "".join(out)


def cmd_convert(args: argparse.Namespace) -> int:
    from ..chips.tmc4210 import units

    try:
        f = units.check_f_clk(args.f_clk)
        lines = [f"f_CLK = {f:g} Hz  PULSE_DIV = {args.pulse_div}"
                 + ("" if args.ramp_div is None else f"  RAMP_DIV = {args.ramp_div}")]
        if args.velocity is not None:
            lines.append(f"velocity {args.velocity} -> R = {units.step_rate(args.velocity, args.pulse_div, f):.6g} Hz")
        if args.hz is not None:
            v = units.velocity_for_rate(args.hz, args.pulse_div, f)
            lines.append(f"R = {args.hz:g} Hz -> velocity {v} (exact R = {units.step_rate(v, args.pulse_div, f):.6g} Hz)")
        if args.a_max is not None or args.hz_per_s is not None:
            if args.ramp_div is None:
                raise CliError("acceleration needs -r/--ramp-div")
            if args.a_max is not None:
                dr = units.rate_change(args.a_max, args.pulse_div, args.ramp_div, f)
                lines.append(f"A_MAX {args.a_max} -> dR = {dr:.6g} Hz/s")
            else:
                a = units.a_max_for_rate_change(args.hz_per_s, args.pulse_div, args.ramp_div, f)
                lines.append(f"dR = {args.hz_per_s:g} Hz/s -> A_MAX {a} "
                             f"(exact dR = {units.rate_change(a, args.pulse_div, args.ramp_div, f):.6g} Hz/s)")
        if len(lines) == 1:
            raise CliError("give a velocity (-v/--hz) and/or an acceleration (-a/--hz-per-s)")
    except units.UnitError as exc:
        raise CliError(str(exc)) from None
    except OverflowError:  # e.g. --hz-per-s 1e300: beyond every register value
        raise CliError("a value is far outside the register ranges (velocity -2047..2047, A_MAX 0..2047)") from None
    print("\n".join(lines))
    return 0


def cmd_trace(args: argparse.Namespace) -> int:
    from ..chips.tmc4210 import TMC4210, ChipError
    from ..chips.tmc4210.script import ScriptError, format_trace, run_file

    try:
        chip = TMC4210(f_clk=args.f_clk)
    except ChipError as exc:
        raise CliError(str(exc)) from None
    chip.add_trace(lambda t, a, b: print(format_trace(t, a, b), flush=True))
    try:
        run_file(chip, args.script)
    except (ScriptError, ChipError) as exc:
        raise CliError(str(exc)) from None
    except BrokenPipeError:
        raise
    except OSError as exc:
        raise CliError(f"cannot read {args.script}: {exc.strerror or exc}") from None
    print(f"# end at t = {chip.time:.6f} s: X_ACTUAL = {chip.x_actual}, V_ACTUAL = {chip.v_actual}, "
          f"INT = {int(chip.interrupt)}")
    return 0


__all__ = ["register", "format_pmulpdiv"]
