# surface reader/writer tests
