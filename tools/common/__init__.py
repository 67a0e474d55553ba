"""Image reading and the one rRMSE (images.py)."""
