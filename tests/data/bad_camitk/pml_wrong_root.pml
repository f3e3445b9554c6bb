<?xml version="1.0"?>
<loads>
</loads>
