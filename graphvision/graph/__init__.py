"""The graph model (:class:`~graphvision.graph.model.Graph`), pipeline files (YAML in,
YAML out, every problem with its file and line), the order of a graph's steps, and its
drawing (SVG, DOT, Mermaid). It knows no node: checking ops is the compiler's job."""
