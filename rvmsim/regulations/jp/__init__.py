"""Japan's rear-view monitor assessment (JNCAP's poles) where it asks more than R158:
its site (``site.yaml``), the ECs JP-1 … JP-4 (``ecs.py``) and the criteria set ``jp``
(``criteria.yaml``).

Importing this package imports nothing: the criteria loader imports ``ecs`` as a plugin
when a criteria file names it, and the site and criteria files are read as data.
"""
