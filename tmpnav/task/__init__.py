"""Stage 6: the task level: encode the cost table as PDDL (unified-planning), solve it with
ENHSP, decode the plan (the only package that imports unified_planning)."""
