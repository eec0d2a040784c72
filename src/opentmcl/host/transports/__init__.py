"""Concrete transports, one module each, chosen by URL scheme (see `opentmcl.host.connect`).

- `inprocess`: a virtual module in the same process (``sim://``), no thread, no socket;
- `tcp`, `serial`, `can`: real links (written against `opentmcl.host.transport.Transport`).
"""
