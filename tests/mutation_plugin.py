"""pytest plugin loaded only by the mutation run ([tool.mutmut] pytest_add_cli_args, docs/mutation.md).

mutmut routes every call of a mutated function through a trampoline, which adds stack frames: the
assembler's deepest legal expression (MAX_EXPR_DEPTH levels, tests/lang/test_assembler.py) would
then hit Python's default recursion limit of 1000 before the assembler's own limit is reached.

Mutants live in the Python code, so the run takes the pure-Python request path (OPENTMCL_PURE=1,
set before opentmcl is imported): the compiled accelerator would bypass mutated functions.
"""
import os
import sys

os.environ["OPENTMCL_PURE"] = "1"  # opentmcl/accel.py: no compiled request path

sys.setrecursionlimit(max(sys.getrecursionlimit(), 20_000))
