//! The OpenPose networks: COCO-18 body model on candle (from `body_pose_model.pth`) and ONNX exports on ort.
