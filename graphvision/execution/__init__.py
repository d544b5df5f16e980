"""Running compiled graphs: the scheduler, the executors (sync, threads, processes, Dask),
one run, a batch over files, a sweep over parameter values, and a run's output folder
with its earlier runs.
It emits events (:class:`~graphvision.execution.record.RunHooks`) and knows no HTML:
pages are passed in by the layer above."""
