"""Training the ManiFoundation network (`mani-lab train`): config (`config`), loop, curves and checkpoints
(`trainer`)."""
