"""graphvision's built-in algorithm plugins, one package per family.

Each package is registered through the ``graphvision.plugins`` entry-point
group, exactly as a third-party plugin is. Packages import numpy at the top
and heavier libraries (scipy, scikit-image, imageio) inside the functions, so
that listing nodes stays fast.
"""
