//! Reference path tracer: unbiased ground truth with NEE + MIS, full/direct/indirect images.
