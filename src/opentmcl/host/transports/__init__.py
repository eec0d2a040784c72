"""Concrete transports, one module each, chosen by URL scheme (see `opentmcl.host.connect`).

- `inprocess`: module objects in the same process, no thread, no socket (``sim://`` puts
  virtual modules behind it from `opentmcl.sim`);
- `tcp`, `serial`, `can`: real links (written against `opentmcl.host.transport.Transport`).
"""
