"""Training the ManiFoundation network (`mani train`): config (`config`), loop, curves and checkpoints
(`trainer`)."""
