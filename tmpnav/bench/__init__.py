"""``tmpnav bench``: planning time against the number of rooms or robots (paper, Fig. 3(b), (c)).

``experiment`` is the command's logic (runs, or a replot of a recorded bench.csv, and the
outputs), ``runs`` draws the goals and runs each job in its own ``worker`` process, ``table``
reads and summarises bench.csv. ``regression`` checks the recorded regression plans.
"""
