"""The scenarios shipped with tmpnav, installed as the data package tmpnav.configs (see tmpnav/shipped.py)."""
