"""numba kernels: numpy, numba and math only, no ROS, no rerun (tests enforce this)."""
