"""gloffuse_blender: the Blender side of gloffuse.

Every module but addon.py is bundled by the gloffuse binary (src/generate/bundle.rs)
into one single-file script per job: the modules a job's main imports, dependencies
before dependants, after a header that defines the parameter document. addon.py is
the Blender extension's __init__.py. See docs/ARCHITECTURE.md, "The Blender side".
"""
