"""Rooms from a robot's map: segmentation, doors, landmark candidates, scenario skeleton."""

#: m²: a room larger than this is a hall, split into places (tmpnav.rooms.places); here so that
#: the command line can show it without importing numpy
MAX_AREA = 100.0
