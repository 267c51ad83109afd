"""Tests of the gRPC front end (`service.grpc`)."""
