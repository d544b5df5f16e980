"""What people look at: ``report.html`` and ``report.md``, batch and sweep pages, progress
on a terminal, and results inline in a notebook. Each subscribes to or is handed what
the execution layer produces."""
