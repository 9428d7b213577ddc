"""Files in and out, shared by both paths: video (PyAV), BVH, ASF/AMC, glTF, output rigs."""
