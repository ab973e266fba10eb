//! Image and temporal metrics against the reference: RMSE, relMSE, PSNR, SSIM, FLIP, flicker, latency.
