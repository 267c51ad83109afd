"""Research work on the product's offline pools (`manifoundation.server.offline`): data generation on Ray."""
