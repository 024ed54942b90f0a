"""The PDDL room domains, installed with tmpnav as the data package tmpnav.pddl."""
