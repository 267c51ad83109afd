"""The original LEAP Hand (right): MJCF and fingertip meshes, MIT (see LICENSE here); package data."""
