"""Rooms from a robot's map: segmentation, doors, landmark candidates, scenario skeleton."""
