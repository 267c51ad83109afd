"""Tests of the gRPC front end (`manifoundation.server.api.grpc`)."""
