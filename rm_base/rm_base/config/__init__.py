"""Configuration: the parameter schema, parameter files, the calibration file."""
