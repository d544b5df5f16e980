"""Nodes: the ``@node`` and ``@source`` decorators, what the registry knows of each node
(:class:`~graphvision.nodes.spec.NodeSpec`), code fingerprints, the registry, and plugin
discovery (entry points, local files, the plugin index that lists nodes without
importing them)."""
