"""Package data: our own hand URDFs (Barrett BH8, Kinova 3-finger) and cached convex hulls (LEAP)."""
