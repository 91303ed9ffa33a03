"""FMVSS No. 111 beyond the paper: its test site (``site.yaml``: objects A–G, the
scene's ``test_site`` defaults), the ECs 1-5, 1-6 and 6-1 (``ecs.py``) and the criteria set
``fmvss111-full`` (``criteria.yaml``: the paper's eleven plus those three).

Importing this package imports nothing: the criteria loader imports ``ecs`` as a plugin
when a criteria file names it, and the site and criteria files are read as data.
"""
