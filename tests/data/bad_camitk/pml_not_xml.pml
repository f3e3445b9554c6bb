solid cube
facet normal 0 0 1
