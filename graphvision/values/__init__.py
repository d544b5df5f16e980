"""Values and their port types: what flows along an edge, how it is checked, encoded
(named arrays plus a JSON header: the cache's format and the processes' transport) and
pictured. The bottom layer: it imports only :mod:`graphvision.errors`."""
