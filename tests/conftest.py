import os

# Same thread count everywhere so that determinism checks compare like with like.
os.environ.setdefault("NUMBA_NUM_THREADS", "2")
