"""uvms_jax: JAX-accelerated kinematics, dexterity, scheduling and hardware tools for UVMS."""

__version__ = "0.1.0"
