"""Compiling a graph against a registry: every op, port, type, parameter and reference
checked at once before anything runs, and the schedule of the steps an output needs."""
