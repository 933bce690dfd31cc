"""manip"""
