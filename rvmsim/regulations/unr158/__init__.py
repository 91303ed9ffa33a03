"""UN R158's rear-view camera system field of vision: its test site (``site.yaml``:
three rows of cylinders), the ECs R158-1 … R158-4 (``ecs.py``) and the criteria set
``unr158`` (``criteria.yaml``).

Importing this package imports nothing: the criteria loader imports ``ecs`` as a plugin
when a criteria file names it, and the site and criteria files are read as data.
"""
