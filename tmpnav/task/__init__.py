"""Stage 6: the task level, the only package that imports unified_planning.

``stage.plan_task`` is the entry point: a cost table and goals in, the ordered plan steps
out. ``encodings`` holds the encoding registry, ``encode`` writes the unified-planning
problem, ``solve`` runs ENHSP (or another engine), ``decode`` turns its plan into robot
moves, ``memo`` remembers solved problems, ``export`` writes the PDDL files.
"""
