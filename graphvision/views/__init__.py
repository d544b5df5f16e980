"""What people look at: ``report.html`` and ``report.md``, batch and sweep pages, progress
on a terminal, and results inline in a notebook. Each subscribes to or is handed what
the execution layer produces. How each kind of value is shown (colour bars, label
colours, point clouds, confusion matrices) is :mod:`graphvision.views.viewers`; the
graph's fit, zoom and pan :mod:`graphvision.views.graph_view`; what the report draws
with the studio's own viewers (tinted masks, classifiers, training curves, matches,
epipolar lines, 3-D clouds) :mod:`graphvision.views.scripted`."""
