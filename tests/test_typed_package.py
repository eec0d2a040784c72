"""The package ships its types (PEP 561 `py.typed`; issue 12 item 5).

A user's own code that calls the library wrongly must be caught by their type checker. Without the
marker mypy skips the package ("missing library stubs or py.typed marker") and reports nothing.
"""

import subprocess
import sys


def test_user_code_is_checked_against_the_installed_package(tmp_path):
    """A call with a wrong argument type in code outside the repository is an `arg-type` error."""
    (tmp_path / "user.py").write_text("from opentmcl.host import connect\nmodule = connect(5)\n")
    out = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental", "user.py"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert "import-untyped" not in out.stdout, out.stdout
    assert 'Argument 1 to "connect" has incompatible type "int"' in out.stdout, out.stdout
